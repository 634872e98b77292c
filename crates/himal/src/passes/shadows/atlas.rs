//! S3 local-light shadow atlas allocator (pure CPU): each shadowed point
//! light is unwrapped into six projectors (cube faces), a spot light into
//! one; every projector gets a square power-of-two tile of one atlas, sized
//! by the light's importance (projected size on screen, i.e. range over
//! distance). Property tests: `tests/shadows_atlas.rs`.

use std::collections::HashMap;

use glam::Vec3;

/// One light asking for shadow tiles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasRequest {
    /// Stable id (the light's index in the scene).
    pub light: u32,
    /// Projectors: 6 for a point light, 1 for a spot.
    pub faces: u32,
    /// See [`importance`]; larger gets larger tiles.
    pub importance: f32,
}

/// A square tile of the atlas for one projector, in texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AtlasTile {
    /// The requesting light's id ([`AtlasRequest::light`]).
    pub light: u32,
    /// Projector of that light: the cube face 0..6 of a point light, 0 for a spot.
    pub face: u32,
    /// Left edge in atlas texels.
    pub x: u32,
    /// Top edge in atlas texels.
    pub y: u32,
    /// Edge in texels (a power of two between the allocator's min and max tile).
    pub size: u32,
}

impl AtlasTile {
    /// Whether the two tiles share any texel.
    pub fn overlaps(&self, o: &AtlasTile) -> bool {
        self.x < o.x + o.size
            && o.x < self.x + self.size
            && self.y < o.y + o.size
            && o.y < self.y + self.size
    }
}

/// Importance of a light of `range` at `position` for a camera at `camera`:
/// its projected size, range / distance, 1 when the camera is inside it.
pub fn importance(position: Vec3, range: f32, camera: Vec3) -> f32 {
    let d = position.distance(camera);
    (range / d.max(range)).clamp(0.0, 1.0)
}

/// Tile sizes by importance with hysteresis, then Morton-order placement.
pub struct AtlasAllocator {
    /// Atlas edge in texels (a power of two).
    pub size: u32,
    /// Smallest tile edge in texels (a power of two).
    pub min_tile: u32,
    /// Largest tile edge in texels (a power of two).
    pub max_tile: u32,
    /// Tile edge each light had last frame (hysteresis).
    previous: HashMap<u32, u32>,
}

impl AtlasAllocator {
    /// `size`, `min_tile` and `max_tile` are rounded to powers of two.
    pub fn new(size: u32, min_tile: u32, max_tile: u32) -> Self {
        let size = size.max(1).next_power_of_two();
        let min_tile = min_tile.max(1).next_power_of_two().min(size);
        Self {
            size,
            min_tile,
            max_tile: max_tile.next_power_of_two().clamp(min_tile, size),
            previous: HashMap::new(),
        }
    }

    /// Edge wanted for importance `w`: max_tile·w rounded down to a power of
    /// two; a light keeps last frame's edge while log2 of its wish stays
    /// within [-0.25, +1.25) of it, so jitter in importance never flips tiles.
    fn wanted(&self, light: u32, w: f32) -> u32 {
        let level = (self.max_tile as f32 * w.max(1e-6)).log2();
        if let Some(&p) = self.previous.get(&light) {
            let lp = (p as f32).log2();
            if level >= lp - 0.25 && level < lp + 1.25 {
                return p;
            }
        }
        let edge = 2f32.powf(level.floor()) as u32;
        edge.clamp(self.min_tile, self.max_tile)
    }

    /// Tiles for this frame. Sizes follow importance; when they do not fit,
    /// the least important light with a tile above the minimum is halved,
    /// and below that the least important lights lose their shadows. Tiles
    /// are placed largest first, then by light id, along a Z-order curve, so
    /// they stay put while no size changes.
    pub fn allocate(&mut self, requests: &[AtlasRequest]) -> Vec<AtlasTile> {
        let mut order: Vec<&AtlasRequest> = requests.iter().filter(|r| r.faces > 0).collect();
        order.sort_by(|a, b| {
            b.importance
                .total_cmp(&a.importance)
                .then(a.light.cmp(&b.light))
        });
        let mut sizes: Vec<u32> = order
            .iter()
            .map(|r| self.wanted(r.light, r.importance))
            .collect();
        // Keep sizes non-increasing in importance (hysteresis may break it).
        for i in 1..sizes.len() {
            sizes[i] = sizes[i].min(sizes[i - 1]);
        }
        let capacity = self.size as u64 * self.size as u64;
        let area = |order: &[&AtlasRequest], sizes: &[u32]| -> u64 {
            order
                .iter()
                .zip(sizes)
                .map(|(r, &s)| r.faces as u64 * s as u64 * s as u64)
                .sum()
        };
        while area(&order, &sizes) > capacity {
            match sizes.iter().rposition(|&s| s > self.min_tile) {
                Some(i) => sizes[i] /= 2,
                None => {
                    order.pop();
                    sizes.pop();
                }
            }
        }
        let mut tiles: Vec<AtlasTile> = order
            .iter()
            .zip(&sizes)
            .flat_map(|(r, &size)| {
                (0..r.faces).map(move |face| AtlasTile {
                    light: r.light,
                    face,
                    x: 0,
                    y: 0,
                    size,
                })
            })
            .collect();
        tiles.sort_by(|a, b| {
            b.size
                .cmp(&a.size)
                .then(a.light.cmp(&b.light))
                .then(a.face.cmp(&b.face))
        });
        // Units of min_tile along a Z-order curve: a tile of m x m units starts
        // at a multiple of m² (all before it are as large), so it is aligned.
        let mut cursor = 0u64;
        for t in &mut tiles {
            let m = (t.size / self.min_tile) as u64;
            let (ux, uy) = morton_decode(cursor);
            t.x = ux * self.min_tile;
            t.y = uy * self.min_tile;
            cursor += m * m;
        }
        self.previous = order
            .iter()
            .zip(&sizes)
            .map(|(r, &s)| (r.light, s))
            .collect();
        tiles
    }
}

/// (x, y) of Z-order index `i` (even bits x, odd bits y).
fn morton_decode(i: u64) -> (u32, u32) {
    let compact = |mut v: u64| {
        v &= 0x5555_5555_5555_5555;
        v = (v | (v >> 1)) & 0x3333_3333_3333_3333;
        v = (v | (v >> 2)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v >> 4)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v >> 8)) & 0x0000_ffff_0000_ffff;
        v = (v | (v >> 16)) & 0x0000_0000_ffff_ffff;
        v as u32
    };
    (compact(i), compact(i >> 1))
}
