//! `himal aa-patterns` prints the A5 table beside the talk's numbers.

mod common;

fn himal(args: &[&str]) -> (bool, String, String) {
    common::run(args, &[])
}

#[test]
fn prints_every_pattern_with_the_talks_numbers() {
    let (ok, out, err) = himal(&["aa-patterns", "--angles", "90", "--offsets", "100"]);
    assert!(ok, "aa-patterns failed: {err}");
    for needle in [
        "1x centre",
        "2x rotated grid",
        "quincunx",
        "4x uniform",
        "4x rotated grid",
        "FLIPQUAD",
        "0.364",
        "0.439",
        "0.518",
        "0.698",
        ">1.0",
    ] {
        assert!(out.contains(needle), "output lacks {needle}:\n{out}");
    }
    // FLIPQUAD's E (column 4) is below 1x centre's.
    let e = |name: &str| -> f64 {
        let line = out.lines().find(|l| l.starts_with(name)).expect("row");
        let cols: Vec<&str> = line[16..].split_whitespace().collect();
        cols[2].parse().expect("E is a number")
    };
    assert!(e("FLIPQUAD") < e("1x centre"));
}

#[test]
fn bad_reference_width_is_rejected() {
    let (ok, _, err) = himal(&["aa-patterns", "--reference-width", "0.5"]);
    assert!(!ok);
    assert!(err.contains("--reference-width 0.5"), "{err}");
}
