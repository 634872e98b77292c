//! A1: himal's generated SMAA lookup textures against the reference
//! implementation's (`../shared/assets/reference/smaa`).

use himal::passes::aa::smaa::lut::{AREA_SIZE, SEARCH_SIZE, area_texture, search_texture};

fn reference(name: &str) -> Vec<u8> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/assets/reference/smaa/"
    )
    .to_string()
        + name;
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[test]
fn search_texture_matches_the_reference_exactly() {
    let ours = search_texture();
    let theirs = reference("SearchTex.raw");
    assert_eq!(theirs.len(), SEARCH_SIZE.0 * SEARCH_SIZE.1);
    // Measured 2026-11-22: 0 texels differ.
    let differ = ours.iter().zip(&theirs).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} search texels differ");
}

#[test]
fn orthogonal_area_tables_match_the_reference() {
    let ours = area_texture();
    let theirs = reference("AreaTex.raw");
    let (w, h) = AREA_SIZE;
    assert_eq!(theirs.len(), w * h * 2);
    let (mut max, mut sum, mut n) = (0u8, 0u64, 0u64);
    for y in 0..h {
        for x in 0..80 {
            for c in 0..2 {
                let i = (y * w + x) * 2 + c;
                let d = ours[i].abs_diff(theirs[i]);
                max = max.max(d);
                sum += d as u64;
                n += 1;
            }
        }
    }
    let mean = sum as f64 / n as f64;
    println!("orthogonal area: max |diff| {max}, mean {mean:.4} (of 255)");
    // Measured 2026-11-22: max 1, mean 0.11 (rounding of the 8-bit values).
    assert!(max <= 1, "max difference {max}");
    assert!(mean < 0.2, "mean difference {mean}");
}

#[test]
fn diagonal_area_tables_match_the_reference() {
    let ours = area_texture();
    let theirs = reference("AreaTex.raw");
    let (w, h) = AREA_SIZE;
    let (mut max, mut sum, mut n, mut differ) = (0u8, 0u64, 0u64, 0u64);
    for y in 0..h {
        for x in 80..w {
            for c in 0..2 {
                let i = (y * w + x) * 2 + c;
                let d = ours[i].abs_diff(theirs[i]);
                max = max.max(d);
                sum += d as u64;
                differ += (d > 0) as u64;
                n += 1;
            }
        }
    }
    let mean = sum as f64 / n as f64;
    println!(
        "diagonal area: max |diff| {max}, mean {mean:.4} (of 255), {differ} of {n} values differ"
    );
    // Measured 2026-11-22: max 1, mean 0.34 (of 255), 30351 of 89600 values
    // differ: the reference truncates (int(255 a)), himal rounds like the
    // orthogonal half; truncating instead leaves 20 values 1 apart (mean 0.0002).
    assert!(max <= 1, "max difference {max}");
    assert!(mean < 0.5, "mean difference {mean}");
}
