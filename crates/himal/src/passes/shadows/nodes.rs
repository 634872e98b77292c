//! The shadow passes as frame-graph nodes: cascades, static slice, hero,
//! atlas, the mask, and the debug view (planned by `ShadowPass::update`).

use super::*;
use crate::graph::{BufferAccess, Fallback};
use crate::passes::cull::Culled;

/// One sun view's depth node: `lists` (and, with `culled`, the GPU list
/// they name) into layer `target.1` of `target.0` (cleared to the far
/// plane first when `target.2`), seen through `ShadowPass::views[view]`.
/// `keep`: never culled by the graph (read by a later frame).
struct DepthNode<'s, 'a> {
    id: &'s str,
    view: usize,
    target: (TextureHandle, u32, bool),
    pipelines: &'a DepthPipelines,
    lists: &'a DrawLists,
    culled: Option<Culled>,
    keep: bool,
}
use crate::passes::common::view_node;

impl ShadowPass {
    /// Adds the shadow nodes; returns the mask, or `None` when shadows are off
    /// (no plan this frame). `view` is the frame constant.
    /// `culled`: the GPU-culled lists the cascades draw (V6).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        gbuffer: GBuffer,
        scene: &'a SceneGpu,
        culled: Option<Culled>,
        extra: Option<&'a dyn CascadeCaster>,
    ) -> Option<TextureHandle> {
        let plan = self.plan.as_ref()?;
        let n = self.cascade_resolution;
        let mut desc = TextureDesc::new_2d(n, n, SHADOW_FORMAT);
        desc.depth_or_layers = CASCADES as u32;
        let mut cascades = graph.create_texture("shadow.cascades", desc);
        for (i, (_, lists)) in plan.cascades.iter().enumerate() {
            let id = format!("shadows.cascade{i}");
            let target = (cascades, i as u32, true);
            let node = DepthNode {
                id: &id,
                view: i,
                target,
                pipelines: &self.depth32,
                lists,
                culled,
                keep: false,
            };
            cascades = self.depth_node(graph, scene, node);
            if let Some(c) = extra {
                cascades = c.add_cascade(graph, cascades, i as u32, &self.views[i]);
            }
        }
        let cascades = (!plan.cascades.is_empty()).then_some(cascades);
        // The static slice writes the back map, outside the graph's pool.
        let mut static_written = None;
        if let (Some((update, lists)), Some((_, maps))) = (&plan.static_update, &self.static_maps) {
            let name = if update.target == 0 {
                "shadow.static0"
            } else {
                "shadow.static1"
            };
            let h = graph.import_texture(name, &maps[update.target]);
            let target = (h, 0, update.clear);
            let depth16 = &self.depth16;
            // The back map is read in a later frame: keep the pass even unread.
            let node = DepthNode {
                id: "shadows.static",
                view: CASCADES,
                target,
                pipelines: depth16,
                lists,
                culled: None,
                keep: true,
            };
            let h = self.depth_node(graph, scene, node);
            static_written = Some((update.target, h));
        }
        let hero_map = plan.hero.as_ref().map(|(_, lists)| {
            let r = self.hero_resolution;
            let map = graph.create_texture("shadow.hero", TextureDesc::new_2d(r, r, SHADOW_FORMAT));
            let target = (map, 0, true);
            let depth32 = &self.depth32;
            let node = DepthNode {
                id: "shadows.hero",
                view: CASCADES + 1,
                target,
                pipelines: depth32,
                lists,
                culled: None,
                keep: false,
            };
            self.depth_node(graph, scene, node)
        });
        let atlas_map = (!plan.projectors.is_empty()).then(|| self.add_atlas(graph, scene, plan));
        // The shown static map: this frame's slice when it just completed,
        // else the front map of an earlier frame.
        let shown = self.static_state.shown.map(|(i, _)| i);
        let static_map = match (static_written, shown, &self.static_maps) {
            (Some((i, h)), Some(s), _) if i == s => Some(h),
            (_, Some(s), Some((_, maps))) => {
                let name = if s == 0 {
                    "shadow.static0"
                } else {
                    "shadow.static1"
                };
                Some(graph.import_texture(name, &maps[s]))
            }
            _ => None,
        };
        let mask = graph.create_texture(
            "shadow.mask",
            TextureDesc::new_2d(size.0, size.1, MASK_FORMAT),
        );
        let hero = hero_map.is_some();
        let far = Fallback::DepthFar;
        let written = graph
            .raster("shadows.mask", &self.mask_program)
            .pipeline(Ok(self.mask.clone()))
            .uniform("params", &self.params)
            .read("depth", gbuffer.depth)
            .read("gbuffer_frame", gbuffer.frame)
            .optional_array("cascades", cascades, far)
            .optional_array("static_map", static_map, far)
            .optional_array("hero_map", hero_map, far)
            .optional_array("atlas", atlas_map, far)
            .uniform("local_lights", &self.local_lights)
            .uniform("light_tiles", &self.light_tiles)
            .sampler("shadow_sampler", &self.sampler)
            .color(mask, wgpu::LoadOp::Clear(wgpu::Color::WHITE))
            .record(move |_, rp| {
                rp.draw(0..3, 0..1);
                // Ryse's hero blend: min into R over the mask just drawn.
                if hero {
                    rp.set_pipeline(&self.hero_blend);
                    rp.draw(0..3, 0..1);
                }
                Ok(())
            });
        written.colors.first().copied()
    }

    /// One sun view's depth node ([`DepthNode`]); returns the map's new version.
    fn depth_node<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        node: DepthNode<'_, 'a>,
    ) -> TextureHandle {
        let DepthNode {
            id,
            view,
            target,
            pipelines,
            lists,
            culled,
            keep,
        } = node;
        let culled = culled.filter(|_| lists.gpu_view.is_some());
        let (map, layer, clear) = target;
        let ops = wgpu::Operations {
            load: if clear {
                wgpu::LoadOp::Clear(1.0)
            } else {
                wgpu::LoadOp::Load
            },
            store: wgpu::StoreOp::Store,
        };
        let node = graph
            .raster(id, &self.depth_program)
            .uniform("shadow", &self.views[view])
            .uniform("objects", &scene.objects);
        let mut node = match culled {
            Some(c) => node
                .read_buffer("instances", c.instances, BufferAccess::StorageRead)
                .indirect(c.args),
            None => node.uniform("instances", &scene.instances),
        }
        .depth(map, Some(layer_view_desc(layer)), ops);
        if keep {
            node = node.side_effect();
        }
        node.record(move |ctx, rp| {
            let culled = culled.as_ref().map(|c| (c, ctx.buffer(c.args)));
            pipelines.draw_culled(rp, scene, lists, culled);
            Ok(())
        })
        .depth
        .unwrap_or(map)
    }

    /// Every projector into its atlas tile: one render pass, a viewport and
    /// a view bind group per tile.
    fn add_atlas<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        plan: &'a FramePlan,
    ) -> TextureHandle {
        let n = self.atlas_resolution;
        let map = graph.create_texture("shadow.atlas", TextureDesc::new_2d(n, n, SHADOW_FORMAT));
        let ops = wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        };
        graph
            .raster("shadows.atlas", &self.depth_program)
            .external_group(0)
            .depth(map, None, ops)
            .record(move |ctx, rp| {
                scene.bind_geometry(rp);
                let views = &self.atlas_views[..plan.projectors.len()];
                for (p, buffer) in plan.projectors.iter().zip(views) {
                    let bg = self.depth_program.bind(
                        ctx.device,
                        0,
                        &[
                            ("shadow", buffer.as_entire_binding()),
                            ("objects", scene.objects.as_entire_binding()),
                            ("instances", scene.instances.as_entire_binding()),
                        ],
                    )?;
                    let t = p.tile;
                    let (x, y, edge) = (t.x as f32, t.y as f32, t.size as f32);
                    rp.set_viewport(x, y, edge, edge, 0.0, 1.0);
                    rp.set_bind_group(0, &bg, &[]);
                    self.depth32.draw_pipelines(rp, scene, &p.draws);
                }
                Ok(())
            })
            .depth
            .unwrap_or(map)
    }

    /// `--view shadow-mask | cascades` from the mask into `output`.
    pub fn add_view<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        kind: ShadowView,
        mask: TextureHandle,
        depth: TextureHandle,
        output: TextureHandle,
    ) -> TextureHandle {
        let id = kind.id();
        let node = view_node(ctx, graph, &self.view_program, "shadows.view", id, output);
        node.uniform("params", &self.params)
            .read("depth", depth)
            .read("mask", mask)
            .draw()
    }
}
