//! Shadow settings of a frame (`FrameSettings::shadows`) and the debug views.

use crate::Error;

/// `--shadows off|csm|csm+static` (the cascade edge `FrameSettings::shadow_resolution`
/// = 0 also turns shadows off).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ShadowMode {
    /// No sun shadows: the sun lights everything.
    Off,
    /// S1: four dynamic cascades.
    #[default]
    Csm,
    /// S1 + S2: the far cascade replaced by the static map once it is filled.
    CsmStatic,
}

impl std::str::FromStr for ShadowMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s {
            "off" => Ok(ShadowMode::Off),
            // `sun` was the single-map mode before the cascades; kept as an alias.
            "csm" | "sun" => Ok(ShadowMode::Csm),
            "csm+static" => Ok(ShadowMode::CsmStatic),
            other => Err(Error::InvalidSettings(format!(
                "shadows \"{other}\": expected off, csm or csm+static"
            ))),
        }
    }
}

/// Everything the shadow passes need besides the cascade edge.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Which sun shadow maps are drawn.
    pub mode: ShadowMode,
    /// Cascades cover view distances [camera near, `max_distance`] (m).
    pub max_distance: f32,
    /// Practical split blend: 1 = logarithmic, 0 = uniform.
    pub split_lambda: f32,
    /// Snap each cascade's centre to whole texels (off only to measure crawling).
    pub snap: bool,
    /// Poisson-disk filter radius in texels of the cascade sampled.
    pub filter_radius_texels: f32,
    /// Static map edge in texels (S2).
    pub static_resolution: u32,
    /// Most draws the static map may render in one frame (time slicing).
    pub static_draw_cap: u32,
    /// Hero map edge in texels (S4); 0 = no hero map.
    pub hero_resolution: u32,
    /// Object given the hero map; `None` = the scene's first skinned object,
    /// else its first moving object.
    pub hero: Option<String>,
    /// Local-light shadow atlas edge in texels (S3); 0 = no local shadows.
    pub atlas_resolution: u32,
    /// R3: the author's near and far replace the camera near and
    /// `max_distance`, with fully logarithmic splits (`split_lambda` unused).
    pub cinematic: Option<crate::scene::CinematicShadows>,
    /// Give no atlas tile, projector pass or mask channel to a shadowed
    /// local light with no caster in its reach (its shadow would be all
    /// lit); off only to measure the saving (#23).
    pub skip_casterless: bool,
    /// Draw the hero map's pass of the mask only inside the screen
    /// rectangle of its light-space box (exact: outside it the pass writes
    /// lit); off only to measure the saving (#23).
    pub hero_scissor: bool,
    /// Classify each 16 x 16 tile of the mask first (`shadows.mask_tiles`):
    /// a map lit or shadowed over the whole tile costs the mask no tap
    /// (exact). Off by default: on lavapipe the pass costs more than the
    /// taps it saves (docs/performance.md, #23).
    pub mask_tiles: bool,
    /// glTF MASK and BLEND casters alpha-tested in every sun map and the
    /// atlas (`depth_masked.wgsl`: a leaf card casts its holes); off: cast
    /// as opaque cards (as before issue #22), to compare.
    pub alpha_test: bool,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            mode: ShadowMode::Csm,
            max_distance: 400.0,
            split_lambda: 0.85,
            snap: true,
            filter_radius_texels: 1.5,
            static_resolution: 8192,
            static_draw_cap: 48,
            hero_resolution: 1024,
            hero: None,
            atlas_resolution: 4096,
            cinematic: None,
            skip_casterless: true,
            hero_scissor: true,
            mask_tiles: false,
            alpha_test: true,
        }
    }
}

impl ShadowSettings {
    /// Checks every value is in its range (distance > 1 m, lambda in 0..1, resolutions in range); the error names the value.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: String| Err(Error::InvalidSettings(what));
        if !(self.max_distance > 1.0 && self.max_distance.is_finite()) {
            return bad(format!(
                "shadow max distance {} must be > 1 m",
                self.max_distance
            ));
        }
        if !(0.0..=1.0).contains(&self.split_lambda) {
            return bad(format!(
                "shadow split lambda {} is outside 0..1",
                self.split_lambda
            ));
        }
        if !(16..=16384).contains(&self.static_resolution) {
            return bad(format!(
                "static shadow map edge {} is outside 16..16384",
                self.static_resolution
            ));
        }
        if let Some(c) = self.cinematic
            && !(c.near > 0.0 && c.far > c.near && c.far.is_finite())
        {
            return bad(format!(
                "cinematic shadows near {} and far {}: need 0 < near < far",
                c.near, c.far
            ));
        }
        if self.static_draw_cap == 0 {
            return bad("static shadow draw cap must be at least 1".into());
        }
        if self.hero_resolution > 8192 {
            return bad(format!(
                "hero shadow map edge {} is above 8192",
                self.hero_resolution
            ));
        }
        if self.atlas_resolution > 16384 {
            return bad(format!(
                "shadow atlas edge {} is above 16384",
                self.atlas_resolution
            ));
        }
        Ok(())
    }
}

/// Shadow debug views (`--view shadow-mask`, `--view cascades`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShadowView {
    /// The mask: R sun (cascades, static and hero), G/B/A local lights.
    Mask,
    /// Sun visibility tinted by the map each pixel reads: red, green, blue,
    /// yellow = cascades 0-3, magenta = static map, grey = none.
    Cascades,
}

impl ShadowView {
    /// The view shader's `VIEW` constant.
    pub fn id(self) -> u32 {
        match self {
            ShadowView::Mask => 1,
            ShadowView::Cascades => 2,
        }
    }
}
