//! The heads-up overlay: text and timing bars rasterised on the CPU into a
//! small straight-alpha RGBA8 image (an 8x8 bitmap font), which presentation
//! composites over the frame. Cheap to rebuild every frame and identical on
//! every adapter.

use font8x8::UnicodeFonts;

/// Glyph cell in pixels (the font's 8x8 glyphs at scale 1).
pub const GLYPH: u32 = 8;
/// Line height in pixels.
pub const LINE: u32 = 10;
const MARGIN: u32 = 4;
const BAR_WIDTH: u32 = 80;

/// A straight-alpha RGBA8 image, display-encoded (sRGB) colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Overlay {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels row by row, top row first, `width * height` of them.
    pub rgba: Vec<[u8; 4]>,
}

/// What the heads-up display shows: free text lines, then one bar per pass.
#[derive(Clone, Debug, Default)]
pub struct Hud {
    /// Text lines drawn from the top, one per [`LINE`] pixels (characters outside the basic font draw as `?`).
    pub lines: Vec<String>,
    /// (pass id, GPU milliseconds), drawn in the given order.
    pub timings: Vec<(String, f64)>,
}

const PANEL: [u8; 4] = [16, 18, 24, 176];
const TEXT: [u8; 4] = [236, 236, 228, 255];
const BAR: [u8; 4] = [232, 160, 48, 255];

impl Overlay {
    /// An image of `width` x `height` pixels, every one `fill`.
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Self {
        Self {
            width,
            height,
            rgba: vec![fill; (width * height) as usize],
        }
    }

    /// Fills the rectangle, clipped to the image.
    pub fn fill_rect(&mut self, x: u32, y: u32, w: u32, h: u32, color: [u8; 4]) {
        for yy in y..(y + h).min(self.height) {
            for xx in x..(x + w).min(self.width) {
                self.rgba[(yy * self.width + xx) as usize] = color;
            }
        }
    }

    /// Draws `text` with its first glyph's top-left at (x, y); characters
    /// outside the font's basic Latin range are drawn as '?'.
    pub fn text(&mut self, x: u32, y: u32, text: &str, color: [u8; 4]) {
        for (i, c) in text.chars().enumerate() {
            let glyph = font8x8::BASIC_FONTS
                .get(c)
                .or_else(|| font8x8::BASIC_FONTS.get('?'))
                .unwrap_or([0; 8]);
            let x0 = x + i as u32 * GLYPH;
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    // bit 0 is the leftmost pixel
                    if bits & (1 << col) != 0 {
                        self.fill_rect(x0 + col, y + row as u32, 1, 1, color);
                    }
                }
            }
        }
    }

    /// The panel for `hud`: a translucent box with the lines, then one row
    /// per pass with its time and a bar proportional to the largest time.
    pub fn hud(hud: &Hud) -> Self {
        let name_chars = hud.timings.iter().map(|(n, _)| n.len()).max().unwrap_or(0);
        let timing_chars = name_chars + 8; // " 12.34" after the name
        let text_chars = hud
            .lines
            .iter()
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0);
        let timing_width = if hud.timings.is_empty() {
            0
        } else {
            timing_chars as u32 * GLYPH + 4 + BAR_WIDTH
        };
        let width = (text_chars as u32 * GLYPH).max(timing_width) + 2 * MARGIN;
        let rows = (hud.lines.len() + hud.timings.len()) as u32;
        let height = rows * LINE + 2 * MARGIN;
        let mut o = Self::new(width.max(1), height.max(1), PANEL);
        for (i, line) in hud.lines.iter().enumerate() {
            o.text(MARGIN, MARGIN + i as u32 * LINE, line, TEXT);
        }
        let longest = hud.timings.iter().map(|t| t.1).fold(0.0, f64::max);
        for (i, (name, ms)) in hud.timings.iter().enumerate() {
            let y = MARGIN + (hud.lines.len() + i) as u32 * LINE;
            let label = format!("{name:<name_chars$} {ms:7.2}");
            o.text(MARGIN, y, &label, TEXT);
            let bar = if longest > 0.0 {
                ((ms / longest).clamp(0.0, 1.0) * f64::from(BAR_WIDTH)).round() as u32
            } else {
                0
            };
            o.fill_rect(
                MARGIN + timing_chars as u32 * GLYPH + 4,
                y + 1,
                bar,
                GLYPH - 2,
                BAR,
            );
        }
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_land_where_the_font_says() {
        let mut o = Overlay::new(16, 8, [0; 4]);
        o.text(0, 0, "I", [255; 4]);
        let lit: Vec<(u32, u32)> = (0..8)
            .flat_map(|y| (0..16).map(move |x| (x, y)))
            .filter(|&(x, y)| o.rgba[(y * 16 + x) as usize][3] == 255)
            .collect();
        let glyph = font8x8::BASIC_FONTS.get('I').unwrap_or([0; 8]);
        let expected: u32 = glyph.iter().map(|b| b.count_ones()).sum();
        assert_eq!(lit.len() as u32, expected);
        assert!(expected > 0);
        // Nothing spills into the second cell.
        assert!(lit.iter().all(|&(x, _)| x < 8));
    }

    #[test]
    fn bars_are_proportional_to_time() {
        let hud = Hud {
            lines: vec!["himal".into()],
            timings: vec![("a".into(), 4.0), ("b".into(), 1.0)],
        };
        let o = Overlay::hud(&hud);
        let bar_len = |row: u32| {
            let y = MARGIN + row * LINE + 3;
            (0..o.width)
                .filter(|&x| o.rgba[(y * o.width + x) as usize] == BAR)
                .count()
        };
        assert_eq!(bar_len(1), BAR_WIDTH as usize);
        assert_eq!(bar_len(2), (BAR_WIDTH / 4) as usize);
    }
}
