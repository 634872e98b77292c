//! S2 in a streamed world: the static map is a square of [`WORLD_EXTENT`]
//! around the camera, filled tile by tile into a back map and kept up to
//! date as sectors stream in by rendering again, in place, the texel
//! rectangle each placed sector casts into. Pure CPU planning; the pass
//! records what [`WorldMapState::plan`] returns. Docs: `docs/techniques/S2.md`.

use glam::{Vec2, Vec3};

use super::cascades::{ShadowFit, light_rotation, ortho_fit};
use super::static_map::needs_fill;
use crate::scene::Aabb;

/// Edge of the world's static map (m): 8192² texels give 0.5 m texels, the
/// footprint of a 1080p pixel ~470 m away, where the cascades end.
pub const WORLD_EXTENT: f32 = 4096.0;
/// Tiles per side of a fill: one tile is one fill step.
pub const WORLD_TILES: u32 = 4;
/// Above a streamed sector's highest ground, what stands on it (houses, trees).
pub const OBJECT_HEADROOM: f32 = 40.0;
/// Texels added around a caster's footprint: the 1.5-texel filter disk and
/// the normal offset read that far.
const RECT_MARGIN: u32 = 4;
/// Two waiting rectangles merge when their union wastes at most this many
/// texels (a 256² block): neighbouring sectors become one update.
const MERGE_SLACK: u64 = 256 * 256;
/// Waiting rectangles at most; past it a new one merges into the one it
/// grows least (the queue never grows without bound).
const MAX_WAITING: usize = 32;

/// A texel rectangle of the map: x, y, width, height (row 0 = light-view +y).
pub type Rect = [u32; 4];

fn area(r: &Rect) -> u64 {
    u64::from(r[2]) * u64::from(r[3])
}

fn union(a: &Rect, b: &Rect) -> Rect {
    let (x0, y0) = (a[0].min(b[0]), a[1].min(b[1]));
    let (x1, y1) = (
        (a[0] + a[2]).max(b[0] + b[2]),
        (a[1] + a[3]).max(b[1] + b[3]),
    );
    [x0, y0, x1 - x0, y1 - y0]
}

fn contains(a: &Rect, b: &Rect) -> bool {
    b[0] >= a[0] && b[1] >= a[1] && b[0] + b[2] <= a[0] + a[2] && b[1] + b[3] <= a[1] + a[3]
}

/// Texels the union of `a` and `b` covers beyond the two.
fn waste(a: &Rect, b: &Rect) -> u64 {
    area(&union(a, b)).saturating_sub(area(a) + area(b))
}

/// Adds `r` to `queue`: dropped when a waiting rectangle holds it, merged
/// into one it barely grows, else appended (merged into the best one past
/// [`MAX_WAITING`]).
fn enqueue(queue: &mut Vec<Rect>, r: Rect) -> bool {
    if queue.iter().any(|q| contains(q, &r)) {
        return false;
    }
    let best = (queue.iter().enumerate())
        .map(|(i, q)| (waste(q, &r), i))
        .min();
    match best {
        Some((w, i)) if w <= MERGE_SLACK || queue.len() >= MAX_WAITING => {
            queue[i] = union(&queue[i], &r);
        }
        _ => queue.push(r),
    }
    true
}

/// The world's static map: extent, tiles of a fill, caster heights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldMap {
    /// Edge of the square the map covers around the camera, in metres ([`WORLD_EXTENT`]).
    pub extent: f32,
    /// Tiles per side of a fill ([`WORLD_TILES`]); one is rendered per fill step.
    pub tiles: u32,
    /// Lowest and highest caster height (m).
    pub heights: (f32, f32),
}

impl WorldMap {
    /// The default map for casters between `heights` (lowest, highest; metres).
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

    /// Texel rectangle of fill tile `tile` (column `tile % tiles`, row
    /// `tile / tiles` from the top texel row).
    pub fn tile_rect(&self, tile: u32, resolution: u32) -> Rect {
        let edge = resolution / self.tiles;
        let (i, j) = (tile % self.tiles, tile / self.tiles);
        [i * edge, j * edge, edge, edge]
    }

    /// The orthographic fit of `rect` of `fit`: the same light view and
    /// depth mapping over the rectangle, so a point lands on the texel and
    /// depth it has in the whole map (through the rectangle's viewport).
    pub fn rect_fit(&self, fit: &ShadowFit, rect: Rect) -> ShadowFit {
        let t = fit.texel_world;
        let [x, y, w, h] = rect.map(|v| v as f32);
        let min = Vec2::new(fit.min.x + x * t, fit.max.y - (y + h) * t);
        let max = Vec2::new(fit.min.x + (x + w) * t, fit.max.y - y * t);
        let proj = glam::camera::rh::proj::directx::orthographic(
            min.x, max.x, min.y, max.y, -fit.max.z, -fit.min.z,
        );
        ShadowFit {
            light_view_proj: proj * fit.light_rotation,
            light_rotation: fit.light_rotation,
            min: min.extend(fit.min.z),
            max: max.extend(fit.max.z),
            texel_world: t,
            depth_range: fit.depth_range,
        }
    }

    /// The texels of a `resolution`-edge map of `fit` that casters in the
    /// world box `bounds` may write, with the filter's margin; `None`
    /// outside the map.
    pub fn rect_under(&self, fit: &ShadowFit, bounds: &Aabb, resolution: u32) -> Option<Rect> {
        if bounds.is_empty() {
            return None;
        }
        let b = bounds.transform(&fit.light_rotation);
        let t = fit.texel_world;
        let n = resolution as f32;
        let x0 = ((b.min.x - fit.min.x) / t).floor() - RECT_MARGIN as f32;
        let x1 = ((b.max.x - fit.min.x) / t).ceil() + RECT_MARGIN as f32;
        let y0 = ((fit.max.y - b.max.y) / t).floor() - RECT_MARGIN as f32;
        let y1 = ((fit.max.y - b.min.y) / t).ceil() + RECT_MARGIN as f32;
        let (x0, y0) = (x0.clamp(0.0, n) as u32, y0.clamp(0.0, n) as u32);
        let (x1, y1) = (x1.clamp(0.0, n) as u32, y1.clamp(0.0, n) as u32);
        (x1 > x0 && y1 > y0).then_some([x0, y0, x1 - x0, y1 - y0])
    }
}

/// One rectangle of the map rendered this frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TileUpdate {
    /// The rectangle's own fit (its view and culling volume).
    pub fit: ShadowFit,
    /// Texel rectangle: viewport, scissor and cleared area.
    pub rect: Rect,
    /// Which of the two maps is written.
    pub target: usize,
}

/// A fill of a new fit into the back map.
#[derive(Clone, Debug)]
struct Fill {
    fit: ShadowFit,
    centre: Vec2,
    target: usize,
    /// Rectangles still to render, next first: the tiles, then what
    /// streaming changed under tiles already drawn.
    pending: Vec<Rect>,
}

/// Time slicing of the world's static map: a fill of a new fit (first
/// frame, sun turned by [`super::static_map::SUN_EPSILON`], camera more than an eighth of the
/// extent from the map's centre) renders every tile into the back map,
/// nearest the camera first, and is shown when the last is drawn; the
/// rectangles streamed sectors cast into ([`Self::mark_dirty`]) are
/// rendered again in place in the shown map (cleared and drawn whole in one
/// frame, so no frame sees one half done). At most `cap` updates a frame;
/// while both wait, the fill gets half of them (rounded up).
#[derive(Clone, Debug, Default)]
pub struct WorldMapState {
    /// The complete map shown (index into the two maps), its fit and centre.
    pub shown: Option<(usize, ShadowFit, Vec2)>,
    filling: Option<Fill>,
    /// Sun and resolution of the last fill started.
    last: Option<(Vec3, u32)>,
    /// Rectangles of the shown map to render again.
    dirty: Vec<Rect>,
}

impl WorldMapState {
    /// Forgets the shown map, any fill under way and the dirty rectangles.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Rectangles of the shown map waiting to be rendered again.
    pub fn dirty(&self) -> &[Rect] {
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
        let far =
            (self.shown).is_none_or(|(_, _, c)| (eye - c).abs().max_element() > map.extent / 8.0);
        let moved = needs_fill(self.last, sun, resolution);
        if (moved || far) && self.filling.is_none() {
            self.filling = Some(self.start_fill(map, eye, sun, resolution));
            self.last = Some((sun, resolution));
        }
        if whole {
            return self.plan_whole(map, resolution);
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
            for rect in self.dirty.drain(..n) {
                out.push(TileUpdate {
                    fit: map.rect_fit(&fit, rect),
                    rect,
                    target: front,
                });
            }
        }
        if let Some(fill) = &mut self.filling {
            let n = fill_share.min(fill.pending.len());
            for rect in fill.pending.drain(..n) {
                out.push(TileUpdate {
                    fit: map.rect_fit(&fill.fit, rect),
                    rect,
                    target: fill.target,
                });
            }
            if fill.pending.is_empty() {
                // The new map replaces the old; its marks were for the old.
                self.shown = Some((fill.target, fill.fit, fill.centre));
                self.filling = None;
                self.dirty.clear();
            }
        }
        out
    }

    fn start_fill(&self, map: &WorldMap, eye: Vec2, sun: Vec3, resolution: u32) -> Fill {
        let centre = map.centre_for(eye);
        let fit = map.fit(centre, sun, resolution);
        let target = self.shown.map_or(0, |(front, _, _)| 1 - front);
        let c = fit
            .light_rotation
            .transform_point3(Vec3::new(eye.x, 0.0, eye.y));
        let near = |r: &Rect| {
            let f = map.rect_fit(&fit, *r);
            let m = (f.min + f.max) * 0.5;
            (m.x - c.x).hypot(m.y - c.y)
        };
        let mut pending: Vec<Rect> = (0..map.tiles * map.tiles)
            .map(|t| map.tile_rect(t, resolution))
            .collect();
        pending.sort_by(|a, b| near(a).total_cmp(&near(b)));
        Fill {
            fit,
            centre,
            target,
            pending,
        }
    }

    fn plan_whole(&mut self, map: &WorldMap, resolution: u32) -> Vec<TileUpdate> {
        let whole = |fit: ShadowFit, target| TileUpdate {
            fit: map.rect_fit(&fit, [0, 0, resolution, resolution]),
            rect: [0, 0, resolution, resolution],
            target,
        };
        if let Some(fill) = self.filling.take() {
            self.shown = Some((fill.target, fill.fit, fill.centre));
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

    /// Streaming placed casters in `bounds` (world): the rectangle they
    /// cast into is rendered again in the shown map, and in a running fill
    /// where it already drew. Returns the rectangles queued.
    pub fn mark_dirty(&mut self, map: &WorldMap, bounds: &Aabb, resolution: u32) -> u32 {
        let mut queued = 0;
        if let Some((_, fit, _)) = &self.shown
            && let Some(r) = map.rect_under(fit, bounds, resolution)
        {
            queued += u32::from(enqueue(&mut self.dirty, r));
        }
        if let Some(fill) = &mut self.filling
            && let Some(r) = map.rect_under(&fill.fit, bounds, resolution)
        {
            queued += u32::from(enqueue(&mut fill.pending, r));
        }
        queued
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> WorldMap {
        WorldMap::new((-50.0, 1500.0))
    }

    const SUN: Vec3 = Vec3::new(0.5, 0.6, -0.3);
    const N: u32 = 1024;

    /// A rectangle's own fit puts every point at the texel and depth the
    /// whole map's fit does (through the rectangle's viewport), and the
    /// fill's tiles cover the map.
    #[test]
    fn rectangles_map_texel_for_texel() {
        let m = map();
        let fit = m.fit(Vec2::new(300.0, -700.0), SUN, N);
        let to_world = fit.light_rotation.inverse();
        let rects = [
            m.tile_rect(5, N),
            [0, 0, N, N],
            [17, 300, 91, 23],
            m.tile_rect(15, N),
        ];
        let mut hits = 0;
        for k in 0..2000 {
            let f = Vec3::new(
                (k as f32 * 0.618_034).fract(),
                (k as f32 * 0.754_878).fract(),
                (k as f32 * 0.569_840).fract(),
            );
            let p = to_world.transform_point3(fit.min + (fit.max - fit.min) * f);
            let c = fit.light_view_proj.project_point3(p);
            let texel = Vec2::new(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5) * N as f32;
            for rect in rects {
                let sub = m.rect_fit(&fit, rect);
                let t = sub.light_view_proj.project_point3(p);
                if t.x.abs() > 1.0 || t.y.abs() > 1.0 {
                    continue;
                }
                hits += 1;
                let at = Vec2::new(t.x * 0.5 + 0.5, 0.5 - t.y * 0.5)
                    * Vec2::new(rect[2] as f32, rect[3] as f32)
                    + Vec2::new(rect[0] as f32, rect[1] as f32);
                assert!((at - texel).abs().max_element() < 2e-3, "{at} vs {texel}");
                assert!((t.z - c.z).abs() < 1e-5);
                let inside = texel.cmpge(Vec2::new(rect[0] as f32, rect[1] as f32)).all()
                    && texel.x <= (rect[0] + rect[2]) as f32 + 1e-3
                    && texel.y <= (rect[1] + rect[3]) as f32 + 1e-3;
                assert!(inside, "{texel} outside {rect:?}");
            }
        }
        assert!(hits > 2000, "{hits}");
        let covered: u64 = (0..16).map(|t| area(&m.tile_rect(t, N))).sum();
        assert_eq!(covered, u64::from(N) * u64::from(N));
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

    /// The rectangle under a caster holds every texel its box projects to.
    #[test]
    fn the_rectangle_under_a_box_holds_its_footprint() {
        let m = map();
        let fit = m.fit(Vec2::ZERO, SUN, N);
        let b = Aabb::new(Vec3::new(64.0, 100.0, 64.0), Vec3::new(128.0, 140.0, 128.0));
        let r = m.rect_under(&fit, &b, N).expect("inside");
        for k in 0..8 {
            let p = Vec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            let c = fit.light_view_proj.project_point3(p);
            let t = Vec2::new(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5) * N as f32;
            assert!(t.x >= r[0] as f32 && t.x <= (r[0] + r[2]) as f32);
            assert!(t.y >= r[1] as f32 && t.y <= (r[1] + r[3]) as f32);
        }
        // A sector is a small part of a tile.
        assert!(area(&r) * 16 < area(&m.tile_rect(0, N)), "{r:?}");
        let outside = Aabb::new(Vec3::splat(9000.0), Vec3::splat(9100.0));
        assert_eq!(m.rect_under(&fit, &outside, N), None);
    }

    /// A fill renders each tile once, `cap` a frame, into the map not
    /// shown, and is shown when its last tile is; small camera moves keep
    /// the map, larger ones start a fill into the other map.
    #[test]
    fn a_fill_renders_every_tile_once_into_the_back_map() {
        let m = map();
        let mut s = WorldMapState::default();
        let eye = Vec2::new(10.0, 20.0);
        let mut rects = Vec::new();
        for frame in 0..8 {
            let u = s.plan(&m, eye, SUN, N, 2, false);
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
            s.plan(&m, eye, SUN, N, 2, false).is_empty(),
            "nothing changed"
        );
        assert!(
            s.plan(&m, eye + Vec2::new(500.0, 0.0), SUN, N, 2, false)
                .is_empty()
        );
        let u = s.plan(&m, eye + Vec2::new(600.0, 0.0), SUN, N, 2, false);
        assert_eq!(u.len(), 2);
        assert!(u.iter().all(|t| t.target == 1));
        assert_eq!(s.shown.map(|(i, _, _)| i), Some(0));
    }

    /// Streaming queues the rectangle under a sector; neighbours merge into
    /// one update, the queue stays bounded, a running fill draws again what
    /// it already drew, and settling renders everything at once.
    #[test]
    fn streamed_sectors_render_their_rectangles_again() {
        // The map's real edge: 0.5 m texels, a sector 128 of them.
        const FULL: u32 = 8192;
        let m = map();
        let mut s = WorldMapState::default();
        let eye = Vec2::ZERO;
        while s.shown.is_none() {
            s.plan(&m, eye, SUN, FULL, 2, false);
        }
        let sector = |i: i32, j: i32| {
            let o = Vec3::new(i as f32 * 64.0, 100.0, j as f32 * 64.0);
            Aabb::new(o, o + Vec3::new(64.0, 40.0, 64.0))
        };
        assert_eq!(s.mark_dirty(&m, &sector(1, 1), FULL), 1);
        assert_eq!(s.mark_dirty(&m, &sector(1, 1), FULL), 0, "held already");
        assert_eq!(s.mark_dirty(&m, &sector(2, 1), FULL), 1);
        assert_eq!(s.dirty().len(), 1, "neighbours merge");
        for i in 0..200 {
            s.mark_dirty(&m, &sector(-15 + (i % 30), -15 + (i / 30) * 5), FULL);
        }
        assert!(s.dirty().len() <= MAX_WAITING);
        let waiting = s.dirty().to_vec();
        let u = s.plan(&m, eye, SUN, FULL, 2, false);
        assert_eq!(u.len(), 2);
        assert!(u.iter().all(|t| t.target == 0), "in the shown map");
        assert_eq!(u[0].rect, waiting[0]);
        // A fill (the sun turned) draws again what streaming changed under
        // a tile it already drew.
        let sun = Vec3::new(0.6, 0.5, -0.3);
        let first = s.plan(&m, eye, sun, FULL, 2, false);
        assert!(
            first.iter().any(|t| t.target == 1),
            "the fill writes the back map"
        );
        let t = first.iter().find(|t| t.target == 1).expect("fill");
        let centre = (t.fit.min + t.fit.max) * 0.5;
        let p = t.fit.light_rotation.inverse().transform_point3(centre);
        assert!(s.mark_dirty(&m, &Aabb::new(p, p), FULL) >= 1);
        let mut again = false;
        while s.filling() {
            let u = s.plan(&m, eye, sun, FULL, 2, false);
            again |= u
                .iter()
                .any(|u| u.target == 1 && area(&u.rect) < area(&t.rect));
        }
        assert!(again, "the changed rectangle was drawn again in the fill");
        s.mark_dirty(&m, &sector(1, 1), FULL);
        let u = s.plan(&m, eye, sun, FULL, 2, true);
        assert_eq!(u.len(), 1);
        assert_eq!(u[0].rect, [0, 0, FULL, FULL]);
        assert!(s.dirty().is_empty());
    }
}
