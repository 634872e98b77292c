//! CPU twin of `present/present.wgsl`: the overlay blended over the frame on
//! display-encoded values.

use super::Overlay;

/// `frame` (RGBA8, display-encoded, `width` wide) with `overlay` blended at
/// `origin` (pixels, top-left): c = o.rgb · o.a + c · (1 − o.a).
pub fn compose(frame: &[[u8; 4]], width: u32, overlay: &Overlay, origin: [u32; 2]) -> Vec<[u8; 4]> {
    let mut out = frame.to_vec();
    for (i, px) in out.iter_mut().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        px[3] = 255;
        let (Some(ox), Some(oy)) = (x.checked_sub(origin[0]), y.checked_sub(origin[1])) else {
            continue;
        };
        if ox >= overlay.width || oy >= overlay.height {
            continue;
        }
        let o = overlay.rgba[(oy * overlay.width + ox) as usize];
        let a = f32::from(o[3]) / 255.0;
        for c in 0..3 {
            let v = f32::from(o[c]) / 255.0 * a + f32::from(px[c]) / 255.0 * (1.0 - a);
            px[c] = (v * 255.0).round() as u8;
        }
    }
    out
}
