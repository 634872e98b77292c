//! What a terrain is made of: its height data and material layers
//! ([`TerrainDesc`], [`TerrainLayerDesc`], [`DetailKind`]) and the LOD knobs
//! ([`TerrainSettings`]). Plain data, no GPU.

use glam::{Vec2, Vec3};

/// The detail pattern a layer's textures are generated with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DetailKind {
    /// Clumped grass blades with a hue variation.
    Grass,
    /// Ridged rock with strata and grain.
    Rock,
    /// Smooth drifts with glossiness sparkle.
    Snow,
    /// Soil with scattered pebbles.
    Soil,
}

/// One material layer; later layers paint over earlier ones where their
/// height and slope bands hold (the first is the base, everywhere).
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainLayerDesc {
    /// Linear albedo.
    pub albedo: Vec3,
    /// Glossiness in 0..1 (the detail texture varies it around this).
    pub glossiness: f32,
    /// Heights in metres where the layer holds (infinite: no limit).
    pub height: [f32; 2],
    /// Slope angles in degrees from horizontal (0 and 90: no limit).
    pub slope_deg: [f32; 2],
    /// Width in metres of the transition at each height limit.
    pub height_blend: f32,
    /// Width in degrees of the transition at each slope limit.
    pub slope_blend: f32,
    /// Noise amplitude in metres added to the height before the test.
    pub jitter: f32,
    /// The pattern of the layer's procedural detail textures.
    pub detail: DetailKind,
    /// Metres per repeat of the near detail scale (the far one is 7.3x).
    pub detail_scale: f32,
    /// Strength of the detail normal.
    pub normal_strength: f32,
}

impl TerrainLayerDesc {
    /// The streamed world's layers: meadow, soil on slopes, rock on
    /// cliffs, snow above the world's snow line on what is not a cliff.
    pub fn for_world(world: &crate::scene::world::World) -> Vec<Self> {
        let mut layers = Self::alpine();
        for l in &mut layers {
            if l.detail == DetailKind::Snow {
                l.height = [world.desc.shape.snow_line, f32::INFINITY];
                l.height_blend = 60.0;
                l.jitter = 50.0;
            }
        }
        layers
    }

    /// The mean linear albedo `layers` paint at `height` and slope (degrees):
    /// `terrain.wgsl`'s layer weights w_i = c_i prod_{j > i} (1 - c_j)
    /// without the border noise, the detail textures at their mean (x 1)
    /// and the large-scale variation at its mean (0.94). For bakes (L5).
    pub fn mean_albedo(layers: &[Self], height: f32, slope_deg: f32) -> Vec3 {
        use crate::scene::heightfield::band;
        let open = |v: f32, at: f32, no_limit: f32| if v == at { no_limit } else { v };
        let mut weight = Vec::with_capacity(layers.len());
        for (i, l) in layers.iter().enumerate() {
            let c = if i == 0 {
                1.0
            } else {
                band(height, l.height[0], l.height[1], l.height_blend)
                    * band(
                        slope_deg,
                        open(l.slope_deg[0], 0.0, f32::NEG_INFINITY),
                        open(l.slope_deg[1], 90.0, f32::INFINITY),
                        l.slope_blend,
                    )
            };
            weight.iter_mut().for_each(|w| *w *= 1.0 - c);
            weight.push(c);
        }
        let albedo: Vec3 = layers.iter().zip(&weight).map(|(l, w)| l.albedo * *w).sum();
        albedo * 0.94
    }

    /// Grass everywhere, soil on gentle slopes, rock on steep ones, snow high up.
    pub fn alpine() -> Vec<Self> {
        let any = Self {
            albedo: Vec3::new(0.16, 0.22, 0.07),
            glossiness: 0.25,
            height: [f32::NEG_INFINITY, f32::INFINITY],
            slope_deg: [0.0, 90.0],
            height_blend: 0.0,
            slope_blend: 0.0,
            jitter: 0.0,
            detail: DetailKind::Grass,
            detail_scale: 3.0,
            normal_strength: 0.6,
        };
        vec![
            any.clone(),
            Self {
                albedo: Vec3::new(0.24, 0.19, 0.13),
                glossiness: 0.2,
                slope_deg: [18.0, 90.0],
                slope_blend: 8.0,
                detail: DetailKind::Soil,
                detail_scale: 2.0,
                ..any.clone()
            },
            Self {
                albedo: Vec3::new(0.32, 0.3, 0.28),
                glossiness: 0.35,
                slope_deg: [34.0, 90.0],
                slope_blend: 8.0,
                detail: DetailKind::Rock,
                detail_scale: 6.0,
                normal_strength: 0.9,
                ..any.clone()
            },
            Self {
                albedo: Vec3::new(0.85, 0.87, 0.9),
                glossiness: 0.55,
                height: [150.0, f32::INFINITY],
                slope_deg: [0.0, 42.0],
                height_blend: 30.0,
                slope_blend: 10.0,
                jitter: 25.0,
                detail: DetailKind::Snow,
                detail_scale: 4.0,
                normal_strength: 0.4,
            },
        ]
    }
}

/// The terrain's height data and materials (plain data; see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainDesc {
    /// World x, z of the world's min corner.
    pub origin: Vec2,
    /// Sectors per side (160 in the real world).
    pub sectors: u32,
    /// Side of a sector in metres (one fine tile each).
    pub sector_size: f32,
    /// Fine samples per sector side including the shared edge (65: 1 m).
    pub tile_res: u32,
    /// The coarse grid's spacing: `(sectors sector_size / coarse_spacing + 1)^2` samples.
    pub coarse_spacing: f32,
    /// Row-major coarse heights, row = z index.
    pub coarse: Vec<f32>,
    /// Fine tiles resident at most (texture array layers).
    pub fine_slots: u32,
    /// Material layers, base first (1..=[`MAX_LAYERS`](super::MAX_LAYERS)).
    pub layers: Vec<TerrainLayerDesc>,
}

impl TerrainDesc {
    /// A world of `sectors`^2 sectors of 64 m (65 samples per tile side,
    /// 16 m coarse grid, 512 slots, [`TerrainLayerDesc::alpine`]) whose
    /// coarse grid samples `height(x, z)`.
    pub fn from_fn(origin: Vec2, sectors: u32, height: impl Fn(f32, f32) -> f32) -> Self {
        let mut d = Self {
            origin,
            sectors,
            sector_size: 64.0,
            tile_res: 65,
            coarse_spacing: 16.0,
            coarse: Vec::new(),
            fine_slots: 512,
            layers: TerrainLayerDesc::alpine(),
        };
        let n = (sectors as f32 * d.sector_size / d.coarse_spacing).round() as u32 + 1;
        d.coarse = (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                height(
                    origin.x + i as f32 * d.coarse_spacing,
                    origin.y + j as f32 * d.coarse_spacing,
                )
            })
            .collect();
        d
    }

    /// The tile of sector (`sx`, `sz`) sampled from `height(x, z)`.
    pub fn tile_from_fn(&self, sx: u32, sz: u32, height: impl Fn(f32, f32) -> f32) -> Vec<f32> {
        let n = self.tile_res;
        let s = self.sector_size / (n - 1).max(1) as f32;
        let corner = self.origin + Vec2::new(sx as f32, sz as f32) * self.sector_size;
        (0..n * n)
            .map(|k| height(corner.x + (k % n) as f32 * s, corner.y + (k / n) as f32 * s))
            .collect()
    }
}

/// LOD knobs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainSettings {
    /// Target on-screen vertex spacing in pixels at the end of each range:
    /// `r_l = s_l f / target_px`.
    pub target_px: f32,
    /// Ranges scale by `2^lod_bias` (positive: finer farther).
    pub lod_bias: f32,
    /// Continuous morph; off, vertices snap halfway through the morph area
    /// (for the popping comparison).
    pub morph: bool,
    /// The morph area: the last `m` of `[r_{l-1}, r_l]`.
    pub morph_fraction: f32,
    /// Levels are added until the top range reaches this (metres).
    pub view_distance: f32,
}

impl Default for TerrainSettings {
    fn default() -> Self {
        Self {
            target_px: 12.0,
            lod_bias: 0.0,
            morph: true,
            morph_fraction: 0.3,
            view_distance: 6000.0,
        }
    }
}
