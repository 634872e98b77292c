//! Shadow casters on the CPU: per-object bounds, which objects are static
//! (S2) and the per-map draw lists culled against a sun view.

use crate::gpu_scene::{Draw, SceneGpu, cull};
use crate::scene::{Aabb, Object, Scene};

use super::cascades::ShadowFit;

/// The draws of one shadow map: opaque and vegetation (own pipeline), and
/// the GPU-culled view that adds its lists (V6, `passes::cull`).
#[derive(Clone, Debug, Default)]
pub struct DrawLists {
    /// Opaque draws recorded on the CPU.
    pub opaque: Vec<Draw>,
    /// Alpha-tested vegetation draws (their own pipeline).
    pub vegetation: Vec<Draw>,
    /// `Some((view, calls))`: also draw view `view` of the culled lists,
    /// `calls` multi-draws.
    pub gpu_view: Option<(u32, u32)>,
    /// `Some(view)`: also draw the streamed pool's batches of culled view
    /// `view` (the world's static-map tiles; the cascades where the GPU
    /// path is off). Not in [`Self::draw_calls`]: the culling counts them
    /// ([`crate::passes::cull::CullPass::pool_calls`]).
    pub pool_view: Option<u32>,
}

impl DrawLists {
    /// Number of CPU draws (opaque and vegetation; the GPU and pool views not counted).
    pub fn len(&self) -> usize {
        self.opaque.len() + self.vegetation.len()
    }

    /// Whether there is no CPU draw.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Draw calls these lists record in `scene` ([`SceneGpu::draw_calls`]).
    pub fn draw_calls(&self, scene: &SceneGpu) -> u32 {
        scene.draw_calls(&self.opaque)
            + scene.draw_calls(&self.vegetation)
            + self.gpu_view.map_or(0, |(_, calls)| calls)
    }

    /// Empties both lists and drops the GPU and pool views.
    pub fn clear(&mut self) {
        self.opaque.clear();
        self.vegetation.clear();
        self.gpu_view = None;
        self.pool_view = None;
    }
}

/// What the shadow passes know of each object (indexed like the scene's objects).
pub struct Casters {
    /// World bounds over all time (moving objects: the swept path).
    pub bounds: Vec<Aabb>,
    /// Objects that move (`orbit`); they never enter the static map.
    pub moving: Vec<bool>,
    /// Name, mesh bounds and motion of each object (hero fitting).
    pub objects: Vec<(Object, Aabb)>,
    /// Bounds of the whole scene.
    pub scene: Aabb,
}

impl Casters {
    /// Swept bounds, motion flags and mesh bounds of every object of `scene` (in GPU order), and the scene's bounds.
    pub fn from_scene(scene: &Scene) -> Self {
        let mut bounds = Vec::with_capacity(scene.objects.len());
        let mut moving = Vec::with_capacity(scene.objects.len());
        let mut objects = Vec::with_capacity(scene.objects.len());
        for o in crate::gpu_scene::gpu_order(scene)
            .into_iter()
            .map(|i| &scene.objects[i])
        {
            let mesh = scene.meshes.get(o.mesh).map_or_else(
                || Aabb::new(glam::Vec3::ZERO, glam::Vec3::ZERO),
                |m| m.bounds,
            );
            bounds.push(o.swept_bounds(&mesh));
            moving.push(o.motion.is_some());
            objects.push((o.clone(), mesh));
        }
        Self {
            bounds,
            moving,
            objects,
            scene: scene.bounds,
        }
    }

    /// Index of the object called `name`, or of the first skinned object
    /// (a character), or of the first moving object.
    pub fn hero_index(&self, name: Option<&str>) -> Option<usize> {
        let skinned = |o: &Object| {
            (o.motion.as_ref())
                .is_some_and(|m| m.animated.as_ref().is_some_and(|a| a.skin.is_some()))
        };
        match name {
            Some(n) => self.objects.iter().position(|(o, _)| o.name == n),
            None => (self.objects.iter().position(|(o, _)| skinned(o)))
                .or_else(|| self.moving.iter().position(|&m| m)),
        }
    }

    fn is_static(&self, object: usize) -> bool {
        !self.moving.get(object).copied().unwrap_or(true)
    }

    /// Appends to `out` the draws of `scene` that may cast into `fit` and
    /// pass `keep` (`true` = static object): its glTF draws (opaque, MASK
    /// and BLEND materials; the depth pass alpha-tests MASK and BLEND ones,
    /// [`SceneGpu::alpha_caster`]) and, with `objects`, its opaque and vegetation draws
    /// (`false`: the GPU culls those for this map).
    pub fn cull_into(
        &self,
        scene: &SceneGpu,
        fit: &ShadowFit,
        keep: impl Fn(bool) -> bool,
        objects: bool,
        out: &mut DrawLists,
    ) {
        let take = |i: usize, b: &Aabb| keep(self.is_static(i)) && fit.may_cast(b);
        if objects {
            out.opaque
                .extend(cull(&scene.draws_opaque, &self.bounds, take));
            out.vegetation
                .extend(cull(&scene.draws_vegetation, &self.bounds, take));
        }
        let textured = scene.textured_casters();
        out.opaque.extend(cull(textured, &self.bounds, take));
    }

    /// Appends the draws of `scene` whose bounds overlap `region` (a light's reach),
    /// leaving out casters more than `max_extent` across: the terrain would be
    /// drawn into every projector for shadows it hardly casts on itself.
    pub fn cull_local_into(
        &self,
        scene: &SceneGpu,
        region: &Aabb,
        max_extent: f32,
        out: &mut DrawLists,
    ) {
        let take =
            |_: usize, b: &Aabb| b.overlaps(region) && b.extent().max_element() <= max_extent;
        let textured = scene.textured_casters();
        out.opaque.extend(cull(
            scene.draws_opaque.iter().chain(textured),
            &self.bounds,
            take,
        ));
        out.vegetation
            .extend(cull(&scene.draws_vegetation, &self.bounds, take));
    }
}
