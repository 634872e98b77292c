//! S2 static shadow map: one large sun map of the whole scene holding the
//! static objects, rendered once and then only read; it replaces the far
//! cascade. Updates are time-sliced (at most `cap` draws a frame) into a back
//! map that is swapped in when complete, so a moving sun re-renders it
//! progressively while the previous map is still shown.

use std::ops::Range;

use glam::{Vec2, Vec3};

use super::cascades::{ShadowFit, light_rotation, ortho_fit, top_of};
use crate::scene::Aabb;

/// Depth format of the static map: 16 bits as in Ryse (8192² = 128 MB).
pub const STATIC_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth16Unorm;

/// The sun moves this much (radians, ~0.1°) before the map is re-rendered.
pub const SUN_EPSILON: f32 = 0.0017;

/// Orthographic fit around the bounding sphere of `scene`; view-independent.
pub fn static_fit(scene: &Aabb, sun_direction: Vec3, resolution: u32) -> ShadowFit {
    let (center, radius) = if scene.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (scene.center(), (scene.extent().length() * 0.5).max(1e-3))
    };
    let rotation = light_rotation(sun_direction);
    let c = rotation.transform_point3(center);
    let z_near = top_of(rotation, scene).max(c.z + radius);
    ortho_fit(rotation, c, radius, z_near, c.z - radius, resolution)
}

/// This frame's slice of the static draw list.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticUpdate {
    /// Indices into the static draw list.
    pub range: Range<usize>,
    /// Clear the target first (first slice of a fill).
    pub clear: bool,
    /// Which of the two maps is written.
    pub target: usize,
    pub fit: ShadowFit,
}

/// Time slicing of the static map (pure CPU; the pass records what it plans).
#[derive(Clone, Debug, Default)]
pub struct StaticMapState {
    /// The complete map shown (index into the two maps) and its fit.
    pub shown: Option<(usize, ShadowFit)>,
    /// The fill in progress: fit, sun it was made for, next draw index.
    filling: Option<(ShadowFit, Vec3, usize)>,
    /// Sun and resolution of the last fill started.
    last: Option<(Vec3, u32)>,
}

impl StaticMapState {
    /// Forget everything (new scene, resolution change).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Plans this frame: when no fill is running, starts one if the sun moved
    /// by more than [`SUN_EPSILON`] (or the resolution changed); then takes up to `cap`
    /// draws of the `total` static ones. A fill that ends this frame is shown
    /// from this frame on.
    pub fn plan(
        &mut self,
        scene: &Aabb,
        sun_direction: Vec3,
        resolution: u32,
        total: usize,
        cap: usize,
    ) -> Option<StaticUpdate> {
        let sun = sun_direction.normalize_or(Vec3::Y);
        let moved = self.last.is_none_or(|(s, n)| {
            n != resolution || s.dot(sun).clamp(-1.0, 1.0).acos() > SUN_EPSILON
        });
        // A fill in progress finishes first, else a sun moving faster than
        // the fill would never show a map; the next fill catches up.
        if moved && self.filling.is_none() {
            self.filling = Some((static_fit(scene, sun, resolution), sun, 0));
            self.last = Some((sun, resolution));
        }
        let (fit, sun_then, cursor) = self.filling?;
        let target = match self.shown {
            Some((front, _)) => 1 - front,
            None => 0,
        };
        let end = (cursor + cap.max(1)).min(total);
        if end >= total {
            self.shown = Some((target, fit));
            self.filling = None;
        } else {
            self.filling = Some((fit, sun_then, end));
        }
        Some(StaticUpdate {
            range: cursor..end,
            clear: cursor == 0,
            target,
            fit,
        })
    }
}

/// Edge of the world's static map (m): 8192² texels give 0.5 m texels, the
/// footprint of a 1080p pixel ~470 m away, where the cascades end.
pub const WORLD_EXTENT: f32 = 4096.0;
/// Tiles per side of the world's static map: one tile is one fill step.
pub const WORLD_TILES: u32 = 4;
/// Above a streamed sector's highest ground, what stands on it (houses, trees).
pub const OBJECT_HEADROOM: f32 = 40.0;

/// S2 in a streamed world: a square of [`WORLD_EXTENT`] around the camera
/// (not the whole 10 km world), heights `heights` (every caster inside),
/// filled tile by tile ([`TiledMapState`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldMap {
    pub extent: f32,
    pub tiles: u32,
    /// Lowest and highest caster height (m).
    pub heights: (f32, f32),
}

impl WorldMap {
    pub fn new(heights: (f32, f32)) -> Self {
        Self {
            extent: WORLD_EXTENT,
            tiles: WORLD_TILES,
            heights,
        }
    }

    /// Map edge in texels for a requested `resolution`: whole tiles.
    pub fn resolution(&self, resolution: u32) -> u32 {
        (resolution / self.tiles).max(1) * self.tiles
    }

    /// The centre a camera at `eye` (xz) gets: snapped to 1/16 of the
    /// extent, so the same path gives the same fits.
    pub fn centre_for(&self, eye: Vec2) -> Vec2 {
        let step = self.extent / 16.0;
        (eye / step).round() * step
    }

    /// The whole map's fit: the light-view bounding square of the box of
    /// the extent around `centre` and every caster height.
    pub fn fit(&self, centre: Vec2, sun_direction: Vec3, resolution: u32) -> ShadowFit {
        let h = self.extent * 0.5;
        let (lo, hi) = self.heights;
        let world = Aabb::new(
            Vec3::new(centre.x - h, lo, centre.y - h),
            Vec3::new(centre.x + h, hi, centre.y + h),
        );
        let rotation = light_rotation(sun_direction);
        let ls = world.transform(&rotation);
        let c = (ls.min + ls.max) * 0.5;
        let half = ((ls.max - ls.min) * 0.5).truncate().max_element();
        // A caster shares its receiver's light-view x, y but lies toward the
        // sun, up to where the ray from the lowest ground reaches the
        // highest caster: beyond the square under a low sun (a mountain
        // outside it shadowing the valley inside). The near plane goes that
        // far (at most four extents), else those casters would be clipped.
        let sin_elevation = sun_direction.normalize_or(Vec3::Y).y.max(0.05);
        let reach = ((hi - lo) / sin_elevation).min(4.0 * self.extent);
        ortho_fit(rotation, c, half, ls.max.z + reach, ls.min.z, resolution)
    }

    /// Tile `tile` (column `tile % tiles`, row `tile / tiles` from the top
    /// texel row) of `fit`: its own orthographic fit (the same light view and
    /// depth mapping over the tile's square) and texel rectangle (x, y, w, h).
    pub fn tile(&self, fit: &ShadowFit, tile: u32, resolution: u32) -> (ShadowFit, [u32; 4]) {
        let t = self.tiles;
        let (i, j) = (tile % t, tile / t);
        let edge = resolution / t;
        let w = (fit.max.x - fit.min.x) / t as f32;
        // Light-view +y is texel row 0 (uv.y = 0.5 - ndc.y / 2).
        let c = Vec3::new(
            fit.min.x + (i as f32 + 0.5) * w,
            fit.max.y - (j as f32 + 0.5) * w,
            0.0,
        );
        let sub = ortho_fit(fit.light_rotation, c, 0.5 * w, fit.max.z, fit.min.z, edge);
        (sub, [i * edge, j * edge, edge, edge])
    }

    /// Tiles of `fit` that casters in the world box `bounds` may cover.
    pub fn tiles_under(&self, fit: &ShadowFit, bounds: &Aabb) -> Vec<u32> {
        let b = bounds.transform(&fit.light_rotation);
        let t = self.tiles;
        let w = (fit.max.x - fit.min.x) / t as f32;
        let outside = b.max.x < fit.min.x
            || b.min.x > fit.max.x
            || b.max.y < fit.min.y
            || b.min.y > fit.max.y;
        if outside || bounds.is_empty() {
            return Vec::new();
        }
        let cell = |v: f32| ((v / w).floor().max(0.0) as u32).min(t - 1);
        let (i0, i1) = (cell(b.min.x - fit.min.x), cell(b.max.x - fit.min.x));
        let (j0, j1) = (cell(fit.max.y - b.max.y), cell(fit.max.y - b.min.y));
        (j0..=j1)
            .flat_map(|j| (i0..=i1).map(move |i| j * t + i))
            .collect()
    }
}

/// One tile (or, settling, the whole map) rendered this frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TileUpdate {
    /// The tile's own fit (its view and culling volume).
    pub fit: ShadowFit,
    /// Texel rectangle (x, y, w, h): viewport, scissor and cleared area.
    pub rect: [u32; 4],
    /// Which of the two maps is written.
    pub target: usize,
}

/// A fill of a new fit into the back map.
#[derive(Clone, Debug)]
struct TiledFill {
    fit: ShadowFit,
    target: usize,
    /// Tiles still to render, next first.
    pending: Vec<u32>,
}

/// Time slicing of the world's static map (pure CPU): a fill of a new fit
/// (first frame, sun turned by [`SUN_EPSILON`], camera more than an eighth
/// of the extent from the map's centre) renders every tile into the back map,
/// nearest the camera first, and is shown when the last is drawn; tiles of
/// the shown map that streaming changed ([`Self::mark_dirty`]) are rendered
/// again in place (a tile is cleared and drawn whole in one frame, so no
/// frame sees it half done). At most `cap` tiles a frame; while both wait,
/// the fill gets half of them (rounded up).
#[derive(Clone, Debug, Default)]
pub struct TiledMapState {
    /// The complete map shown (index into the two maps), its fit and centre.
    pub shown: Option<(usize, ShadowFit, Vec2)>,
    filling: Option<(TiledFill, Vec2)>,
    /// Sun and resolution of the last fill started.
    last: Option<(Vec3, u32)>,
    /// Tiles of the shown map to render again.
    dirty: Vec<u32>,
}

impl TiledMapState {
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Tiles of the shown map waiting to be rendered again.
    pub fn dirty(&self) -> &[u32] {
        &self.dirty
    }

    /// Whether a fill is in progress.
    pub fn filling(&self) -> bool {
        self.filling.is_some()
    }

    /// Plans this frame for a camera at `eye` (xz). `whole`: render
    /// everything that waits in one update of the whole map (offline
    /// frames: `Renderer::settle_world`).
    pub fn plan(
        &mut self,
        map: &WorldMap,
        eye: Vec2,
        sun_direction: Vec3,
        resolution: u32,
        cap: usize,
        whole: bool,
    ) -> Vec<TileUpdate> {
        let sun = sun_direction.normalize_or(Vec3::Y);
        let far = self
            .shown
            .is_none_or(|(_, _, c)| (eye - c).abs().max_element() > map.extent / 8.0);
        let moved = self.last.is_none_or(|(s, n)| {
            n != resolution || s.dot(sun).clamp(-1.0, 1.0).acos() > SUN_EPSILON
        });
        if (moved || far) && self.filling.is_none() {
            let centre = map.centre_for(eye);
            let fit = map.fit(centre, sun, resolution);
            let target = self.shown.map_or(0, |(front, _, _)| 1 - front);
            let mut pending: Vec<u32> = (0..map.tiles * map.tiles).collect();
            let near = |t: &u32| {
                let (f, _) = map.tile(&fit, *t, resolution);
                let c = fit
                    .light_rotation
                    .transform_point3(Vec3::new(eye.x, 0.0, eye.y));
                let m = (f.min + f.max) * 0.5;
                (m.x - c.x).hypot(m.y - c.y)
            };
            pending.sort_by(|a, b| near(a).total_cmp(&near(b)));
            self.filling = Some((
                TiledFill {
                    fit,
                    target,
                    pending,
                },
                centre,
            ));
            self.last = Some((sun, resolution));
        }
        if whole {
            return self.plan_whole(resolution);
        }
        let cap = cap.max(1);
        let fill_share = match (&self.filling, self.dirty.is_empty()) {
            (Some(_), true) => cap,
            (Some(_), false) => cap.div_ceil(2),
            (None, _) => 0,
        };
        let mut out = Vec::new();
        if let Some((front, fit, _)) = self.shown {
            let n = (cap - fill_share).min(self.dirty.len());
            for t in self.dirty.drain(..n) {
                let (f, rect) = map.tile(&fit, t, resolution);
                out.push(TileUpdate {
                    fit: f,
                    rect,
                    target: front,
                });
            }
        }
        if let Some((fill, centre)) = &mut self.filling {
            let n = fill_share.min(fill.pending.len());
            for t in fill.pending.drain(..n) {
                let (f, rect) = map.tile(&fill.fit, t, resolution);
                out.push(TileUpdate {
                    fit: f,
                    rect,
                    target: fill.target,
                });
            }
            if fill.pending.is_empty() {
                // The new map replaces the old; its marks were for the old.
                self.shown = Some((fill.target, fill.fit, *centre));
                self.filling = None;
                self.dirty.clear();
            }
        }
        out
    }

    fn plan_whole(&mut self, resolution: u32) -> Vec<TileUpdate> {
        let whole = |fit: ShadowFit, target| TileUpdate {
            fit,
            rect: [0, 0, resolution, resolution],
            target,
        };
        if let Some((fill, centre)) = self.filling.take() {
            self.shown = Some((fill.target, fill.fit, centre));
            self.dirty.clear();
            return vec![whole(fill.fit, fill.target)];
        }
        match self.shown {
            Some((front, fit, _)) if !self.dirty.is_empty() => {
                self.dirty.clear();
                vec![whole(fit, front)]
            }
            _ => Vec::new(),
        }
    }

    /// Streaming placed casters in `bounds` (world): the shown map's tiles
    /// under them are rendered again, and so are the fill's tiles already
    /// drawn. Returns how many tiles were marked.
    pub fn mark_dirty(&mut self, map: &WorldMap, bounds: &Aabb) -> u32 {
        let mut marked = 0;
        if let Some((_, fit, _)) = &self.shown {
            for t in map.tiles_under(fit, bounds) {
                if !self.dirty.contains(&t) {
                    self.dirty.push(t);
                    marked += 1;
                }
            }
        }
        if let Some((fill, _)) = &mut self.filling {
            for t in map.tiles_under(&fill.fit, bounds) {
                if !fill.pending.contains(&t) {
                    fill.pending.push(t);
                    marked += 1;
                }
            }
        }
        marked
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> WorldMap {
        WorldMap::new((-50.0, 1500.0))
    }

    const SUN: Vec3 = Vec3::new(0.5, 0.6, -0.3);

    /// A tile's own fit puts every point at the texel and depth the whole
    /// map's fit does (through the tile's viewport).
    #[test]
    fn tiles_partition_the_map_texel_for_texel() {
        let (m, n) = (map(), 1024);
        let fit = m.fit(Vec2::new(300.0, -700.0), SUN, n);
        let mut seen = vec![0u32; 16];
        // Points spread over the map's light-view box, back in the world.
        let to_world = fit.light_rotation.inverse();
        for k in 0..400 {
            let f = Vec3::new(
                (k as f32 * 0.618_034).fract(),
                (k as f32 * 0.754_878).fract(),
                (k as f32 * 0.569_840).fract(),
            );
            let p = to_world.transform_point3(fit.min + (fit.max - fit.min) * f);
            let c = fit.light_view_proj.project_point3(p);
            let texel = Vec2::new(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5) * n as f32;
            let tiles = m.tiles_under(&fit, &Aabb::new(p, p));
            assert_eq!(tiles.len(), 1, "{p} lies in one tile");
            let (sub, rect) = m.tile(&fit, tiles[0], n);
            let t = sub.light_view_proj.project_point3(p);
            assert!(
                t.x.abs() <= 1.0 + 1e-4 && t.y.abs() <= 1.0 + 1e-4,
                "{p} outside its tile"
            );
            let in_tile = Vec2::new(t.x * 0.5 + 0.5, 0.5 - t.y * 0.5) * rect[2] as f32
                + Vec2::new(rect[0] as f32, rect[1] as f32);
            assert!(
                (in_tile - texel).abs().max_element() < 2e-3,
                "{in_tile} vs {texel}"
            );
            assert!((t.z - c.z).abs() < 1e-5);
            seen[tiles[0] as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c > 0), "every tile is hit: {seen:?}");
        // The map holds its extent: every corner of the square projects inside.
        for (x, z) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            for y in [m.heights.0, m.heights.1] {
                let p = Vec3::new(300.0 + x * 2048.0, y, -700.0 + z * 2048.0);
                let c = fit.light_view_proj.project_point3(p);
                let inside = c.abs().truncate().max_element() <= 1.0 + 1e-5;
                assert!(inside && (-1e-5..=1.0 + 1e-5).contains(&c.z), "{p} -> {c}");
            }
        }
    }

    /// A fill renders each tile once, `cap` a frame, nearest the camera
    /// first, into the map not shown, and is shown when its last tile is.
    #[test]
    fn a_fill_renders_every_tile_once_into_the_back_map() {
        let (m, n) = (map(), 1024);
        let mut s = TiledMapState::default();
        let eye = Vec2::new(10.0, 20.0);
        let mut rects = Vec::new();
        for frame in 0..8 {
            let u = s.plan(&m, eye, SUN, n, 2, false);
            assert_eq!(u.len(), 2, "frame {frame}");
            assert!(u.iter().all(|t| t.target == 0));
            rects.extend(u.iter().map(|t| t.rect));
            assert_eq!(
                s.shown.is_some(),
                frame == 7,
                "shown after the last tile only"
            );
        }
        rects.sort();
        rects.dedup();
        assert_eq!(rects.len(), 16, "each tile once");
        assert!(
            s.plan(&m, eye, SUN, n, 2, false).is_empty(),
            "nothing changed"
        );
        // The camera moves less than an eighth of the extent: same map.
        assert!(
            s.plan(&m, eye + Vec2::new(500.0, 0.0), SUN, n, 2, false)
                .is_empty()
        );
        // More: a new fill, into the other map, while the old one is shown.
        let u = s.plan(&m, eye + Vec2::new(600.0, 0.0), SUN, n, 2, false);
        assert_eq!(u.len(), 2);
        assert!(u.iter().all(|t| t.target == 1));
        assert_eq!(s.shown.map(|(i, _, _)| i), Some(0));
    }

    /// Streaming marks the shown map's tiles under a sector and they are
    /// rendered again in place; a fill re-renders the tiles it already drew.
    #[test]
    fn streamed_sectors_render_their_tiles_again() {
        let (m, n) = (map(), 1024);
        let mut s = TiledMapState::default();
        let eye = Vec2::ZERO;
        while s.shown.is_none() {
            s.plan(&m, eye, SUN, n, 2, false);
        }
        let sector = Aabb::new(Vec3::new(64.0, 100.0, 64.0), Vec3::new(128.0, 140.0, 128.0));
        let marked = s.mark_dirty(&m, &sector);
        assert!((1..=4).contains(&marked), "{marked} tiles under one sector");
        assert_eq!(s.mark_dirty(&m, &sector), 0, "marked once");
        let u = s.plan(&m, eye, SUN, n, 2, false);
        assert_eq!(u.len() as u32, marked.min(2));
        assert!(u.iter().all(|t| t.target == 0), "in the shown map");
        // A fill (the sun turned): a tile drawn before a sector arrived
        // is drawn again before the fill is shown.
        let sun = Vec3::new(0.6, 0.5, -0.3);
        let first = s.plan(&m, eye, sun, n, 2, false);
        assert!(
            first.iter().all(|t| t.target == 1),
            "the fill writes the back map"
        );
        let mut drawn = first.len();
        let centre = (first[0].fit.min + first[0].fit.max) * 0.5;
        let p = first[0]
            .fit
            .light_rotation
            .inverse()
            .transform_point3(centre);
        // One tile of the shown map and the fill's tile already drawn.
        assert_eq!(s.mark_dirty(&m, &Aabb::new(p, p)), 2);
        let mut frames = 0;
        while s.filling() {
            let u = s.plan(&m, eye, sun, n, 2, false);
            drawn += u.iter().filter(|t| t.target == 1).count();
            frames += 1;
        }
        assert_eq!(drawn, 17, "16 tiles and one again");
        assert!(frames <= 16);
        // Settling renders everything waiting in one update of the map.
        s.mark_dirty(&m, &sector);
        let u = s.plan(&m, eye, sun, n, 2, true);
        assert_eq!(u.len(), 1);
        assert_eq!(u[0].rect, [0, 0, n, n]);
        assert!(s.dirty().is_empty());
    }
}
