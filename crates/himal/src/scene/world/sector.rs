//! One 64 m sector of the world, generated on its own from the seed and its
//! coordinates: its terrain tile (65 x 65 heights, 1 m apart, edges shared
//! with the neighbours) and its instances (rocks, the forests' larches and
//! rosewoods, and the houses, roofs, fields and fences of villages).

use glam::{Mat4, Quat, Vec2, Vec3};

use super::terrain::{Village, WorldTerrain};
use crate::scene::noise;

/// Edge of a sector in metres (Far Cry 4: 64 m sectors).
pub const SECTOR_SIZE: f32 = 64.0;
/// Height samples per sector edge, both edges included (1 m apart).
pub const TILE_RES: usize = 65;

/// A sector's column (x, west to east) and row (z, north to south).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SectorCoord {
    /// Column, 0 at the west (min x) edge, below the world's sector count.
    pub x: u16,
    /// Row, 0 at the north (min z) edge, below the world's sector count.
    pub z: u16,
}

/// What an instance draws; each kind is one shared mesh of the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum InstanceKind {
    /// A boulder (unit size, noise seed 11); instances scale it.
    Rock0,
    /// A second boulder shape (noise seed 23).
    Rock1,
    /// A third boulder shape (noise seed 37).
    Rock2,
    /// A house's walls: a unit box scaled to the house.
    HouseWalls,
    /// A house's roof: a unit prism scaled to the house.
    Roof,
    /// A crop field: a 1 x 1 m patch of crop rows, scaled to the field.
    Field,
    /// A 4 m fence segment (two posts, two rails).
    Fence,
    /// A conifer of the upper forests (V1's larch: a trunk and a leaves
    /// region, each its own mesh).
    Larch,
    /// A broadleaf of the lower forests (V1's rosewood).
    Rosewood,
    /// A 16 m stretch of the river's surface.
    Water,
}

impl InstanceKind {
    /// The tree species a kind places (`None`: not a tree).
    pub fn species(self) -> Option<crate::scene::tree::Species> {
        match self {
            InstanceKind::Larch => Some(crate::scene::tree::Species::Larch),
            InstanceKind::Rosewood => Some(crate::scene::tree::Species::Rosewood),
            _ => None,
        }
    }

    /// GPU pool regions an instance fills: a tree's trunk and leaves, one
    /// for the rest ([`super::forest::regions`]).
    pub fn regions(self) -> usize {
        1 + usize::from(self.species().is_some())
    }

    /// Every kind, in the order of their GPU instance regions and [`super::PoolSizes::instances`].
    pub const ALL: [InstanceKind; 10] = [
        InstanceKind::Rock0,
        InstanceKind::Rock1,
        InstanceKind::Rock2,
        InstanceKind::HouseWalls,
        InstanceKind::Roof,
        InstanceKind::Field,
        InstanceKind::Fence,
        InstanceKind::Larch,
        InstanceKind::Rosewood,
        InstanceKind::Water,
    ];

    /// Distance culling per class (m from the camera; 0: none, the
    /// streaming radius bounds it): rocks and fences are too small to
    /// matter past a few hundred metres, where they would only shimmer.
    pub fn draw_distance(self) -> f32 {
        // (Trees: every resident one draws; most at the impostor level.)
        match self {
            InstanceKind::Rock0 | InstanceKind::Rock1 | InstanceKind::Rock2 => 700.0,
            InstanceKind::Fence => 500.0,
            _ => 0.0,
        }
    }

    /// Short lower-case name (`rock0`, `house`, `larch`...), as a scene file's pool sizes name the kind.
    pub fn name(self) -> &'static str {
        match self {
            InstanceKind::Rock0 => "rock0",
            InstanceKind::Rock1 => "rock1",
            InstanceKind::Rock2 => "rock2",
            InstanceKind::HouseWalls => "house",
            InstanceKind::Roof => "roof",
            InstanceKind::Field => "field",
            InstanceKind::Fence => "fence",
            InstanceKind::Larch => "larch",
            InstanceKind::Rosewood => "rosewood",
            InstanceKind::Water => "water",
        }
    }
}

/// One placed mesh: the per-instance attributes of V6 (position, rotation
/// about +Y, size, bending, tint).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Which shared mesh it draws.
    pub kind: InstanceKind,
    /// World position of the mesh's local origin.
    pub position: Vec3,
    /// Rotation about +Y (radians).
    pub yaw: f32,
    /// Scale per local axis.
    pub size: Vec3,
    /// Lean in metres at the top (trees, later bent by wind).
    pub bend: f32,
    /// Linear multiplier of the mesh's albedo, 0..1 each (sRGB-free).
    pub tint: [u8; 4],
}

impl Instance {
    /// Local to world: T * Ry * S.
    pub fn transform(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(
            self.size,
            Quat::from_rotation_y(self.yaw),
            self.position,
        )
    }
}

/// A generated sector: what streaming uploads.
#[derive(Clone, Debug, PartialEq)]
pub struct SectorData {
    /// Which sector this is.
    pub coord: SectorCoord,
    /// `TILE_RES`^2 heights, row-major (z rows outer), sample (0, 0) at
    /// the sector's min corner.
    pub heights: Vec<f32>,
    /// Lowest of [`Self::heights`] in metres (the tile's bounds for culling).
    pub min_height: f32,
    /// Highest of [`Self::heights`] in metres.
    pub max_height: f32,
    /// Everything the sector places: rocks, trees, village parts, river stretches.
    pub instances: Vec<Instance>,
}

impl SectorData {
    /// Bytes this sector uploads (tile + instances as the GPU stores them).
    pub fn upload_bytes(&self) -> u64 {
        let records: usize = self.instances.iter().map(|i| i.kind.regions()).sum();
        (self.heights.len() * 4 + records * super::GPU_INSTANCE_BYTES) as u64
    }
}

/// Scene-file rules for what each sector places (`[world.rules]`). The
/// rules that decide where villages stand (`village_chance`,
/// `village_max_rise`) and the tree line are [`WorldShape`](super::WorldShape)'s:
/// village sites are part of the height function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacementRules {
    /// Scales each 8 m cell's chance of a rock (at most one per cell).
    pub rock_density: f32,
    /// Scales each 4 m cell's chance of a tree (at most one per cell).
    pub tree_density: f32,
    /// Steepest ground a tree stands on (degrees from horizontal).
    pub tree_max_slope: f32,
    /// Altitude (m) above which forests are larches, below rosewoods; the
    /// border is mixed by noise over [`LARCH_MIX`] metres either side.
    pub larch_line: f32,
    /// Place villages' houses (walls and roofs).
    pub houses: bool,
    /// Place villages' fields.
    pub fields: bool,
    /// Place the fences around the fields.
    pub fences: bool,
}

impl Default for PlacementRules {
    fn default() -> Self {
        PlacementRules {
            rock_density: 1.0,
            tree_density: 1.0,
            tree_max_slope: 34.0,
            larch_line: 160.0,
            houses: true,
            fields: true,
            fences: true,
        }
    }
}

impl PlacementRules {
    /// Whether a village's instance of `kind` is placed (a fence needs its field).
    fn keeps(&self, kind: InstanceKind) -> bool {
        match kind {
            InstanceKind::HouseWalls | InstanceKind::Roof => self.houses,
            InstanceKind::Field => self.fields,
            InstanceKind::Fence => self.fields && self.fences,
            _ => true,
        }
    }
}

/// SplitMix64: a small, seedable, portable generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}

/// Linear RGB tint in 0..1 to the stored bytes.
fn tint(rgb: [f32; 3]) -> [u8; 4] {
    let b = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [b(rgb[0]), b(rgb[1]), b(rgb[2]), 255]
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The sector's min corner in world x, z.
pub fn sector_origin(world_origin: Vec2, c: SectorCoord) -> Vec2 {
    world_origin + Vec2::new(c.x as f32, c.z as f32) * SECTOR_SIZE
}

/// Generates sector `c` of the world whose min corner is `world_origin`.
pub fn generate(
    terrain: &WorldTerrain,
    rules: &PlacementRules,
    world_origin: Vec2,
    c: SectorCoord,
) -> SectorData {
    let o = sector_origin(world_origin, c);
    let mut heights = Vec::with_capacity(TILE_RES * TILE_RES);
    for j in 0..TILE_RES {
        for i in 0..TILE_RES {
            heights.push(terrain.height(o.x + i as f32, o.y + j as f32));
        }
    }
    let (min_height, max_height) = heights
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &h| (lo.min(h), hi.max(h)));
    let tile = Tile { o, h: &heights };
    let seed = noise::hash_lattice(terrain.shape.seed ^ 0x5ec7_0000, c.x as i32, c.z as i32);
    let mut instances = Vec::new();
    scatter_rocks(terrain, rules, &tile, seed, &mut instances);
    scatter_trees(terrain, rules, &tile, seed, &mut instances);
    place_water(terrain, &tile, &mut instances);
    let centre = o + Vec2::splat(SECTOR_SIZE * 0.5);
    for v in terrain.villages_near(centre, SECTOR_SIZE * std::f32::consts::FRAC_1_SQRT_2) {
        instances.extend(village_layout(v).into_iter().filter(|i| {
            rules.keeps(i.kind) && tile.contains(Vec2::new(i.position.x, i.position.z))
        }));
    }
    SectorData {
        coord: c,
        heights,
        min_height,
        max_height,
        instances,
    }
}

/// The sector's heights with bilinear lookup and slope.
struct Tile<'a> {
    o: Vec2,
    h: &'a [f32],
}

impl Tile<'_> {
    fn contains(&self, p: Vec2) -> bool {
        let l = p - self.o;
        l.x >= 0.0 && l.y >= 0.0 && l.x < SECTOR_SIZE && l.y < SECTOR_SIZE
    }

    fn at(&self, i: usize, j: usize) -> f32 {
        self.h[j.min(TILE_RES - 1) * TILE_RES + i.min(TILE_RES - 1)]
    }

    /// Height at world `p` (inside the tile), on the bilinear surface.
    fn height(&self, p: Vec2) -> f32 {
        let l = (p - self.o).clamp(Vec2::ZERO, Vec2::splat(SECTOR_SIZE));
        let (i, j) = (
            (l.x as usize).min(TILE_RES - 2),
            (l.y as usize).min(TILE_RES - 2),
        );
        let (tx, tz) = (l.x - i as f32, l.y - j as f32);
        let top = self.at(i, j) * (1.0 - tx) + self.at(i + 1, j) * tx;
        let bottom = self.at(i, j + 1) * (1.0 - tx) + self.at(i + 1, j + 1) * tx;
        top * (1.0 - tz) + bottom * tz
    }

    /// Slope in degrees from horizontal at world `p`, from 2 m central differences.
    fn slope(&self, p: Vec2) -> f32 {
        let l = (p - self.o).clamp(Vec2::ONE, Vec2::splat(SECTOR_SIZE - 1.0));
        let (i, j) = (l.x.round() as usize, l.y.round() as usize);
        let dx = (self.at(i + 1, j) - self.at(i - 1, j)) * 0.5;
        let dz = (self.at(i, j + 1) - self.at(i, j - 1)) * 0.5;
        (dx * dx + dz * dz).sqrt().atan().to_degrees()
    }
}

/// Rocks: boulders on steep scree, fewer on meadows and in the river bed.
fn scatter_rocks(
    t: &WorldTerrain,
    rules: &PlacementRules,
    tile: &Tile,
    seed: u32,
    out: &mut Vec<Instance>,
) {
    let mut rng = Rng(seed as u64 ^ 0x0000_7a0c_0000_0000);
    let cell = 8.0;
    let n = (SECTOR_SIZE / cell) as usize;
    let s = &t.shape;
    for j in 0..n {
        for i in 0..n {
            let p = tile.o + Vec2::new(i as f32 + rng.unit(), j as f32 + rng.unit()) * cell;
            let (roll, pick, r1, r2, r3, r4) = (
                rng.unit(),
                rng.next(),
                rng.unit(),
                rng.unit(),
                rng.unit(),
                rng.unit(),
            );
            let slope = tile.slope(p);
            let h = tile.height(p);
            let river = t.river_distance(p.x, p.y) < s.river_width * 1.6;
            let village = t
                .villages_near(p, 0.0)
                .any(|v| t.village_weight(v, p) > 0.0);
            let (chance, lo, hi): (f32, f32, f32) = if village {
                (0.0, 0.0, 0.0)
            } else if slope > 33.0 {
                (0.4, 0.9, 3.6)
            } else if river {
                (0.3, 0.4, 1.4)
            } else if h > s.snow_line - 120.0 {
                (0.18, 0.6, 2.4)
            } else {
                (0.035, 0.3, 1.3)
            };
            // Every roll is drawn whatever the rules: a thinner scatter is a
            // subset of the default one, and the default stays the same.
            if roll >= chance * rules.rock_density {
                continue;
            }
            let size = lo * (hi / lo).powf(r1);
            let kind = [
                InstanceKind::Rock0,
                InstanceKind::Rock1,
                InstanceKind::Rock2,
            ][(pick % 3) as usize];
            let shade = 0.85 + 0.3 * r2;
            out.push(Instance {
                kind,
                // Sunk by a third so no rock floats on a slope.
                position: Vec3::new(p.x, h - 0.3 * size, p.y),
                yaw: r3 * std::f32::consts::TAU,
                size: Vec3::new(size, size * (0.6 + 0.35 * r4), size * (0.8 + 0.3 * r2)),
                bend: 0.0,
                tint: tint([shade, shade * (0.97 + 0.05 * r4), shade * 0.95]),
            });
        }
    }
}

/// The river's surface: a quad per 16 m of its course whose centre line
/// crosses this sector (each stretch belongs to exactly one sector: the
/// course is a function of z), turned along the course, 0.4 m below the
/// banks' water level so the channel's sides hide its edges.
fn place_water(t: &WorldTerrain, tile: &Tile, out: &mut Vec<Instance>) {
    if !matches!(t.source, super::HeightSource::Procedural) {
        return;
    }
    let s = &t.shape;
    let step = 16.0;
    for k in 0..(SECTOR_SIZE / step) as usize {
        let z = tile.o.y + (k as f32 + 0.5) * step;
        let x = t.river_x(z);
        if x < tile.o.x || x >= tile.o.x + SECTOR_SIZE {
            continue;
        }
        let slope = (t.river_x(z + 4.0) - t.river_x(z - 4.0)) / 8.0;
        out.push(Instance {
            kind: InstanceKind::Water,
            position: Vec3::new(x, t.river_level(z) - 0.4, z),
            // Local +z along the course (x' = slope per metre of z).
            yaw: slope.atan(),
            size: Vec3::new(
                3.0 * s.river_width,
                1.0,
                step * (1.0 + slope * slope).sqrt() + 1.0,
            ),
            bend: 0.0,
            tint: [255; 4],
        });
    }
}

/// Half width (m) of the altitude band where larch and rosewood stands mix.
pub const LARCH_MIX: f32 = 60.0;

/// The species of a tree at `p`, altitude `h`: larch above the larch line,
/// rosewood below, the border moved up and down by noise in stands of
/// about 40 m (a pure function of the world's seed and the place).
pub fn tree_kind(t: &WorldTerrain, rules: &PlacementRules, p: Vec2, h: f32) -> InstanceKind {
    let seed = noise::hash_lattice(t.shape.seed, 0x1a, 0x7c);
    let f = noise::Fractal {
        octaves: 2,
        ..Default::default()
    };
    let border = rules.larch_line + LARCH_MIX * noise::fbm(seed, p.x / 40.0, p.y / 40.0, f);
    if h >= border {
        InstanceKind::Larch
    } else {
        InstanceKind::Rosewood
    }
}

/// Forest mask: large patches with ragged edges, about [-1, 1].
pub fn forest_mask(t: &WorldTerrain, p: Vec2) -> f32 {
    let seed = noise::hash_lattice(t.shape.seed, 0xf0, 0x7e);
    let f = noise::Fractal {
        octaves: 4,
        ..Default::default()
    };
    noise::fbm(seed, p.x / 1100.0, p.y / 1100.0, f)
        + 0.35 * noise::fbm(seed ^ 1, p.x / 160.0, p.y / 160.0, f)
}

/// Trees where the forest mask is high, below the tree line, on slopes
/// under `tree_max_slope` (34 degrees), away from the river and outside
/// villages; larches above the larch line, rosewoods below ([`tree_kind`]).
fn scatter_trees(
    t: &WorldTerrain,
    rules: &PlacementRules,
    tile: &Tile,
    seed: u32,
    out: &mut Vec<Instance>,
) {
    let mut rng = Rng(seed as u64 ^ 0x0000_0000_7ee5_0000);
    // 625 trees/ha at most: closed forests (FC4's Kyrat) of >= 50,000 trees within 1 km.
    let cell = 4.0;
    let n = (SECTOR_SIZE / cell) as usize;
    let s = &t.shape;
    for j in 0..n {
        for i in 0..n {
            let p = tile.o + Vec2::new(i as f32 + rng.unit(), j as f32 + rng.unit()) * cell;
            let (roll, r1, r2, r3, r4) =
                (rng.unit(), rng.unit(), rng.unit(), rng.unit(), rng.unit());
            let h = tile.height(p);
            let line = s.tree_line + 40.0 * (r4 - 0.5);
            // Density: the mask's strength, thinning over the last 80 m below the line.
            let density =
                smoothstep(0.0, 0.35, forest_mask(t, p)) * (1.0 - smoothstep(line - 80.0, line, h));
            if roll >= density * rules.tree_density || tile.slope(p) > rules.tree_max_slope {
                continue;
            }
            if t.river_distance(p.x, p.y) < s.river_width * 3.0
                || t.villages_near(p, 0.0)
                    .any(|v| t.village_weight(v, p) > 0.0)
            {
                continue;
            }
            let scale = 0.65 + 0.7 * r1;
            let green = 0.8 + 0.35 * r2;
            out.push(Instance {
                kind: tree_kind(t, rules, p, h),
                position: Vec3::new(p.x, h - 0.2, p.y),
                yaw: r3 * std::f32::consts::TAU,
                size: Vec3::splat(scale),
                bend: 0.0,
                tint: tint([0.85 + 0.2 * r4, green, 0.9]),
            });
        }
    }
}

/// A village's houses (walls + roof), fields and the fences around them, a
/// pure function of the village.
pub fn village_layout(v: &Village) -> Vec<Instance> {
    let mut rng = Rng(v.seed as u64 | 0x1111_0000_0000_0000);
    let along = Vec2::new(v.street.cos(), v.street.sin());
    let across = Vec2::new(-along.y, along.x);
    let at = |a: f32, c: f32| v.center + along * a + across * c;
    // glam's Ry turns +x toward -z: the yaw that points local +x along the street.
    let yaw = -v.street;
    let mut out = Vec::new();
    const PLASTER: [[f32; 3]; 4] = [
        [0.80, 0.77, 0.70],
        [0.78, 0.70, 0.55],
        [0.70, 0.68, 0.66],
        [0.62, 0.50, 0.40],
    ];
    const ROOF: [[f32; 3]; 3] = [[0.45, 0.16, 0.10], [0.30, 0.22, 0.18], [0.24, 0.25, 0.28]];
    for k in -3..=3 {
        for side in [-1.0f32, 1.0] {
            if rng.unit() > 0.8 {
                continue;
            }
            let (w, d, wall) = (
                rng.range(6.0, 9.0),
                rng.range(6.0, 8.0),
                rng.range(3.0, 4.5),
            );
            let turn = rng.range(-0.07, 0.07);
            let p = at(
                k as f32 * 16.0 + rng.range(-1.5, 1.5),
                side * (6.5 + d * 0.5),
            );
            let base = Vec3::new(p.x, v.height, p.y);
            out.push(Instance {
                kind: InstanceKind::HouseWalls,
                position: base,
                yaw: yaw + turn,
                size: Vec3::new(w, wall, d),
                bend: 0.0,
                tint: tint(PLASTER[(rng.next() % 4) as usize]),
            });
            out.push(Instance {
                kind: InstanceKind::Roof,
                position: base + Vec3::Y * wall,
                yaw: yaw + turn,
                size: Vec3::new(w + 0.8, rng.range(2.0, 3.2), d + 0.8),
                bend: 0.0,
                tint: tint(ROOF[(rng.next() % 3) as usize]),
            });
        }
    }
    const CROPS: [[f32; 3]; 4] = [
        [0.62, 0.52, 0.25],
        [0.35, 0.50, 0.18],
        [0.40, 0.30, 0.20],
        [0.55, 0.55, 0.22],
    ];
    for (sa, sc) in [(-1.0f32, -1.0f32), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        if rng.unit() > 0.85 {
            continue;
        }
        let (w, d) = (rng.range(26.0, 34.0), rng.range(22.0, 30.0));
        let (ca, cc) = (
            sa * rng.range(36.0, 40.0),
            sc * (18.0 + d * 0.5 + rng.range(0.0, 3.0)),
        );
        let p = at(ca, cc);
        out.push(Instance {
            kind: InstanceKind::Field,
            position: Vec3::new(p.x, v.height + 0.02, p.y),
            yaw,
            size: Vec3::new(w, 1.0, d),
            bend: 0.0,
            tint: tint(CROPS[(rng.next() % 4) as usize]),
        });
        // Fence segments (4 m long along local x) around the field.
        let fence = |a: f32, c: f32, along_x: bool, out: &mut Vec<Instance>| {
            let q = at(ca + a, cc + c);
            out.push(Instance {
                kind: InstanceKind::Fence,
                position: Vec3::new(q.x, v.height, q.y),
                yaw: if along_x {
                    yaw
                } else {
                    yaw - std::f32::consts::FRAC_PI_2
                },
                size: Vec3::ONE,
                bend: 0.0,
                tint: tint([0.9, 0.85, 0.8]),
            });
        };
        let (hw, hd) = (w * 0.5 + 1.0, d * 0.5 + 1.0);
        let (nw, nd) = (
            (2.0 * hw / 4.0).round() as i32,
            (2.0 * hd / 4.0).round() as i32,
        );
        for i in 0..nw {
            let a = -hw + 2.0 + i as f32 * 4.0;
            fence(a, -hd, true, &mut out);
            fence(a, hd, true, &mut out);
        }
        for i in 0..nd {
            let c = -hd + 2.0 + i as f32 * 4.0;
            fence(-hw, c, false, &mut out);
            fence(hw, c, false, &mut out);
        }
    }
    out
}
