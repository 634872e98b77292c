//! The world's height function: ridged mountains in massifs, rolling hills,
//! a river winding south to north through a valley it carves, and villages
//! levelled on flat ground. A pure function of the seed and (x, z): any
//! sample, and so any sector, is produced on its own.
//!
//! Equations and figures: `docs/world.md` ("Height").

use glam::Vec2;

use crate::scene::HeightGrid;
use crate::scene::noise::{self, Fractal};

/// Shape parameters of the procedural world (metres).
#[derive(Clone, Debug, PartialEq)]
pub struct WorldShape {
    /// Seed of every noise and village draw (same seed, same world).
    pub seed: u32,
    /// Peak height of the tallest massifs above the river.
    pub mountain_height: f32,
    /// Cycles per metre of the ridges (1/1800: crests ~1.8 km apart).
    pub mountain_frequency: f32,
    /// Height of the rolling hills everywhere.
    pub hill_height: f32,
    /// Water surface height at the south edge (z = +half) ...
    pub river_level: f32,
    /// ... rising by this much to the north edge (it flows south).
    pub river_rise: f32,
    /// Half width of the river channel.
    pub river_width: f32,
    /// Depth of the river bed below the water surface at the centre line.
    pub river_depth: f32,
    /// Distance from the river over which the valley floor rises into the land.
    pub valley_width: f32,
    /// Lateral swing of the river's course.
    pub meander: f32,
    /// Villages: one candidate site per cell of this many metres.
    pub village_cell: f32,
    /// Probability that a cell's site holds a village (where the ground allows).
    pub village_chance: f32,
    /// Largest rise or fall of the natural ground a village radius from a
    /// site's centre that levelling may take (the blend makes it a bank).
    pub village_max_rise: f32,
    /// Level ground radius of a village, and the blend back to the land.
    pub village_radius: f32,
    /// Width of the bank from a village's level ground back to the natural land.
    pub village_blend: f32,
    /// Height above which snow lies (jittered by the terrain shader).
    pub snow_line: f32,
    /// Highest forests.
    pub tree_line: f32,
}

impl Default for WorldShape {
    fn default() -> Self {
        WorldShape {
            seed: 7,
            mountain_height: 1150.0,
            mountain_frequency: 1.0 / 1800.0,
            hill_height: 45.0,
            river_level: 60.0,
            river_rise: 90.0,
            river_width: 14.0,
            river_depth: 3.0,
            valley_width: 520.0,
            meander: 1100.0,
            village_cell: 768.0,
            village_chance: 0.55,
            village_max_rise: 24.0,
            village_radius: 110.0,
            village_blend: 120.0,
            snow_line: 720.0,
            tree_line: 560.0,
        }
    }
}

/// Where the heights come from.
#[derive(Clone, Debug, PartialEq)]
pub enum HeightSource {
    /// [`WorldShape`]'s mountains, hills and river.
    Procedural,
    /// A height map stretched over the whole world (column 0 at the west
    /// edge, row 0 at the north edge); no river is carved.
    Image(HeightGrid),
}

/// A village: levelled ground at `height` around `center`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Village {
    /// Centre (x, z) in world metres.
    pub center: Vec2,
    /// Height of the levelled ground in metres.
    pub height: f32,
    /// Direction of its main street (radians from +x).
    pub street: f32,
    /// Seed of its layout (houses, fields, fences).
    pub seed: u32,
}

/// The river's course at one z (the same for a whole row of samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RiverRow {
    /// Centre line x.
    pub x: f32,
    /// Cosine of the course's angle to z (0 where there is no river).
    pub cos: f32,
    /// Water surface height.
    pub level: f32,
}

impl RiverRow {
    /// Horizontal distance from (x, this row) to the centre line.
    pub fn distance(&self, x: f32) -> f32 {
        if self.cos == 0.0 {
            f32::INFINITY
        } else {
            (x - self.x).abs() * self.cos
        }
    }
}

/// The height function with its village sites (derived from the seed once;
/// a few hundred samples).
#[derive(Clone, Debug)]
pub struct WorldTerrain {
    /// Shape parameters of the procedural heights (and the snow and tree lines).
    pub shape: WorldShape,
    /// Procedural heights or a height map.
    pub source: HeightSource,
    /// World extent: min corner and edge length (metres).
    pub origin: Vec2,
    /// Edge length of the square world in metres.
    pub extent: f32,
    /// One entry per village cell (row-major, z outer), `None` where none stands.
    villages: Vec<Option<Village>>,
    village_cells: usize,
}

const MOUNTAIN: Fractal = Fractal {
    octaves: 9,
    lacunarity: 2.0,
    gain: 0.5,
};
const SMOOTH: Fractal = Fractal {
    octaves: 3,
    lacunarity: 2.0,
    gain: 0.5,
};

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl WorldTerrain {
    /// The terrain of a world whose min corner is `origin`, `extent` metres on a side.
    pub fn new(shape: WorldShape, source: HeightSource, origin: Vec2, extent: f32) -> Self {
        let cells = (extent / shape.village_cell).ceil().max(1.0) as usize;
        let mut t = WorldTerrain {
            shape,
            source,
            origin,
            extent,
            villages: Vec::new(),
            village_cells: cells,
        };
        // Sites in cell order; one whose levelled ground would reach an
        // earlier village's is dropped, so every village is level.
        let apart = 2.0 * (t.shape.village_radius + t.shape.village_blend);
        for i in 0..cells * cells {
            let site = t
                .site(i % cells, i / cells)
                .filter(|v| t.villages().all(|o| o.center.distance(v.center) > apart));
            t.villages.push(site);
        }
        t
    }

    fn seed(&self, k: u32) -> u32 {
        noise::hash_lattice(self.shape.seed, k as i32, 0x5eed)
    }

    /// Height of the land before villages level it.
    pub fn natural_height(&self, x: f32, z: f32) -> f32 {
        self.natural_height_in(x, z, &self.river_row(z))
    }

    /// [`Self::natural_height`] with the row's river course given.
    pub fn natural_height_in(&self, x: f32, z: f32, river: &RiverRow) -> f32 {
        match &self.source {
            HeightSource::Procedural => {
                let s = &self.shape;
                let d = river.distance(x);
                // Valley: the land rises from the river over `valley_width`.
                let rise = smoothstep(s.river_width, s.valley_width, d);
                let channel = 1.0 - smoothstep(0.4 * s.river_width, 1.4 * s.river_width, d);
                let land = if rise > 0.0 { self.land(x, z) } else { 0.0 };
                river.level + 1.0 + rise * land - (s.river_depth + 1.0) * channel * channel
            }
            HeightSource::Image(g) => {
                let c = self.origin + Vec2::splat(self.extent * 0.5);
                let s = g.size[0] / self.extent;
                g.height_at((x - c.x) * s, (z - c.y) * s).unwrap_or(0.0)
            }
        }
    }

    /// Mountains in massifs plus hills, >= 0 above the river's level.
    fn land(&self, x: f32, z: f32) -> f32 {
        let s = &self.shape;
        let f = s.mountain_frequency;
        // Domain warp bends the ridges.
        let wx = x + 380.0 * noise::fbm(self.seed(1), x * f * 0.5, z * f * 0.5, SMOOTH);
        let wz = z + 380.0 * noise::fbm(self.seed(2), x * f * 0.5 + 5.2, z * f * 0.5, SMOOTH);
        let ridges = noise::ridged(self.seed(3), wx * f, wz * f, MOUNTAIN, 0.35);
        let massif = smoothstep(
            -0.05,
            0.5,
            noise::fbm(self.seed(4), x * f * 0.3, z * f * 0.3, SMOOTH),
        );
        let hills = 0.5 + 0.5 * noise::eroded_fbm(self.seed(5), x / 420.0, z / 420.0, SMOOTH, 1.0);
        s.mountain_height * massif * ridges * (0.35 + 0.65 * ridges) + s.hill_height * hills
    }

    /// The river's water surface height at `z`.
    pub fn river_level(&self, z: f32) -> f32 {
        let north = ((self.origin.y + self.extent - z) / self.extent).clamp(0.0, 1.0);
        self.shape.river_level + self.shape.river_rise * north
    }

    /// The river's centre line: x as a function of z.
    pub fn river_x(&self, z: f32) -> f32 {
        let m = self.shape.meander;
        let center = self.origin.x + self.extent * 0.5;
        center
            + m * noise::fbm(self.seed(6), z / 2600.0, 0.37, SMOOTH)
            + 0.25 * m * noise::fbm(self.seed(7), z / 700.0, 1.91, SMOOTH)
    }

    /// What every sample of the row at `z` shares: the river's course there.
    pub fn river_row(&self, z: f32) -> RiverRow {
        if !matches!(self.source, HeightSource::Procedural) {
            return RiverRow {
                x: 0.0,
                cos: 0.0,
                level: 0.0,
            };
        }
        let h = 4.0;
        let slope = (self.river_x(z + h) - self.river_x(z - h)) / (2.0 * h);
        RiverRow {
            x: self.river_x(z),
            cos: 1.0 / (1.0 + slope * slope).sqrt(),
            level: self.river_level(z),
        }
    }

    /// Horizontal distance to the river's centre line (first order: the
    /// offset in x times the cosine of the course's angle); infinite for
    /// height maps.
    pub fn river_distance(&self, x: f32, z: f32) -> f32 {
        self.river_row(z).distance(x)
    }

    /// The cell's village: the most level of 16 candidate spots, if it is
    /// level enough, dry and below the tree line.
    fn site(&self, cx: usize, cz: usize) -> Option<Village> {
        let s = &self.shape;
        let h = noise::hash_lattice(self.seed(8), cx as i32, cz as i32);
        if noise::hash_to_unit(h) >= s.village_chance {
            return None;
        }
        let cell = Vec2::new(cx as f32, cz as f32) * s.village_cell;
        let margin = s.village_radius + s.village_blend;
        let inside = |p: Vec2| {
            p.cmpge(self.origin + margin).all() && p.cmple(self.origin + self.extent - margin).all()
        };
        let r = s.village_radius;
        let mut best: Option<(f32, Vec2, f32)> = None;
        for k in 0..16 {
            let u = noise::hash_to_unit(noise::hash_lattice(h, 1, k));
            let v = noise::hash_to_unit(noise::hash_lattice(h, 2, k));
            let center =
                self.origin + cell + Vec2::new(0.15 + 0.7 * u, 0.15 + 0.7 * v) * s.village_cell;
            if !inside(center) {
                continue;
            }
            let height = self.natural_height(center.x, center.y);
            let d = self.river_distance(center.x, center.y);
            // Its levelled ground (radius + blend) stays clear of the channel.
            if d < s.river_width * 2.0 + r + s.village_blend || height > s.tree_line - 40.0 {
                continue;
            }
            // Roughness: the largest rise or fall a radius away.
            let rough = [
                (r, 0.0),
                (-r, 0.0),
                (0.0, r),
                (0.0, -r),
                (0.7 * r, 0.7 * r),
                (-0.7 * r, -0.7 * r),
            ]
            .iter()
            .map(|(dx, dz)| (self.natural_height(center.x + dx, center.y + dz) - height).abs())
            .fold(0.0f32, f32::max);
            if best.is_none_or(|b| rough < b.0) {
                best = Some((rough, center, height));
            }
        }
        // Levelling blends the rise over the blend margin (24 m over 120 m: a 1:5 bank).
        let (rough, center, height) = best?;
        if rough > s.village_max_rise {
            return None;
        }
        let street = noise::hash_to_unit(noise::hash_lattice(h, 3, 0)) * std::f32::consts::PI;
        Some(Village {
            center,
            height,
            street,
            seed: noise::hash_lattice(h, 4, 0),
        })
    }

    /// Villages whose levelled ground reaches within `reach` of `p`.
    pub fn villages_near(&self, p: Vec2, reach: f32) -> impl Iterator<Item = &Village> {
        let s = &self.shape;
        let r = reach + s.village_radius + s.village_blend;
        let cell =
            |v: f32| ((v / s.village_cell).floor() as i64).clamp(0, self.village_cells as i64 - 1);
        let lo = (p - self.origin - r).to_array().map(cell);
        let hi = (p - self.origin + r).to_array().map(cell);
        let n = self.village_cells;
        (lo[1]..=hi[1])
            .flat_map(move |cz| (lo[0]..=hi[0]).map(move |cx| cz as usize * n + cx as usize))
            .filter_map(|i| self.villages[i].as_ref())
            .filter(move |v| v.center.distance(p) <= r)
    }

    /// Every village of the world.
    pub fn villages(&self) -> impl Iterator<Item = &Village> {
        self.villages.iter().flatten()
    }

    /// Weight of a village's levelling at `p`: 1 inside its radius, 0 beyond the blend.
    pub fn village_weight(&self, v: &Village, p: Vec2) -> f32 {
        let s = &self.shape;
        1.0 - smoothstep(
            s.village_radius,
            s.village_radius + s.village_blend,
            v.center.distance(p),
        )
    }

    /// Height of the ground at (x, z): the land, levelled where villages stand.
    pub fn height(&self, x: f32, z: f32) -> f32 {
        self.height_in(x, z, &self.river_row(z))
    }

    /// [`Self::height`] with the row's river course given (rows of a grid
    /// share it: a third of the cost of a sample).
    pub fn height_in(&self, x: f32, z: f32, river: &RiverRow) -> f32 {
        let p = Vec2::new(x, z);
        let mut h = self.natural_height_in(x, z, river);
        for v in self.villages_near(p, 0.0) {
            let w = self.village_weight(v, p);
            h += (v.height - h) * w;
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn world() -> WorldTerrain {
        WorldTerrain::new(
            WorldShape::default(),
            HeightSource::Procedural,
            Vec2::splat(-5120.0),
            10240.0,
        )
    }

    #[test]
    fn river_runs_below_its_banks_and_mountains_rise() {
        let t = world();
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        for i in 0..64 {
            let z = -5000.0 + i as f32 * 156.0;
            let x = t.river_x(z);
            let water = t.river_level(z);
            let bed = t.height(x, z);
            assert!(bed < water, "river bed {bed} above water {water} at z {z}");
            for j in 0..32 {
                let v = t.height(-5000.0 + j as f32 * 312.0, z);
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        eprintln!("heights [{lo}, {hi}] m, villages {}", t.villages().count());
        // Measured [66.8, 1277] m and 41 villages on 2026-12-02 (seed 7).
        assert!(hi > 700.0, "no mountains above the snow line: {hi}");
        assert!(lo > 0.0, "ground below sea level: {lo}");
        assert!(t.villages().count() >= 20, "too few villages");
    }

    #[test]
    fn villages_are_level() {
        let t = world();
        for v in t.villages() {
            for k in 0..8 {
                let a = k as f32 * std::f32::consts::FRAC_PI_4;
                let p = v.center + Vec2::new(a.cos(), a.sin()) * t.shape.village_radius * 0.9;
                let h = t.height(p.x, p.y);
                assert!(
                    (h - v.height).abs() < 1e-3,
                    "village at {:?} not level: {h} vs {}",
                    v.center,
                    v.height
                );
            }
        }
    }
}
