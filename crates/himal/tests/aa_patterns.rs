//! A5: the pattern study reproduces the talk's ranking
//! (FLIPQUAD < 4x RG < quincunx < 4x uniform < 1x).

use himal::passes::aa::patterns::{PatternResult, StudySettings, study};

fn e(r: &[PatternResult], name: &str) -> f64 {
    match r.iter().find(|p| p.name == name) {
        Some(p) => p.e,
        None => panic!("pattern {name} missing from the study"),
    }
}

#[test]
fn ranking_matches_the_talk() {
    let settings = StudySettings {
        angles: 360,
        offsets: 200,
        ..StudySettings::default()
    };
    let r = study(settings);
    for p in &r {
        println!(
            "{:16} rms {:.4} E {:.3} talk {:?}",
            p.name, p.rms, p.e, p.talk
        );
    }
    let order = [
        "FLIPQUAD",
        "4x rotated grid",
        "quincunx",
        "4x uniform",
        "1x centre",
    ];
    for w in order.windows(2) {
        let (a, b) = (e(&r, w[0]), e(&r, w[1]));
        // Smallest gap measured 2026-11-22: FLIPQUAD 0.407 vs 4x RG 0.467
        // (0.06); a gap under 0.02 would be a tie, not a ranking.
        assert!(a + 0.02 < b, "{} {a:.3} is not below {} {b:.3}", w[0], w[1]);
    }
    assert!(e(&r, "1x centre") > 1.0);
}

#[test]
fn a_pixel_box_reference_loses_the_ranking() {
    // The documented sensitivity: with a 1-pixel reference box FLIPQUAD's
    // shared boundary samples count as error and it falls behind 4x RG
    // (measured 0.612 vs 0.392 on 2026-11-22).
    let settings = StudySettings {
        angles: 180,
        offsets: 200,
        reference_width: 1.0,
        ..StudySettings::default()
    };
    let r = study(settings);
    assert!(e(&r, "FLIPQUAD") > e(&r, "4x rotated grid") + 0.1);
}
