//! The shadow passes as frame-graph nodes: cascades, static slice, hero,
//! atlas, the mask, and the debug view (planned by `ShadowPass::update`).

use super::*;
use crate::passes::common::view_node;

impl ShadowPass {
    /// Adds the shadow nodes; returns the mask, or `None` when shadows are off
    /// (no plan this frame).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        gbuffer: GBuffer,
        view: &'a wgpu::Buffer,
        scene: &'a SceneGpu,
    ) -> Option<TextureHandle> {
        let plan = self.plan.as_ref()?;
        let (g_depth, g_frame) = (gbuffer.depth, gbuffer.frame);
        let n = self.cascade_resolution;
        let mut desc = TextureDesc::new_2d(n, n, SHADOW_FORMAT);
        desc.depth_or_layers = CASCADES as u32;
        let mut cascades = graph.create_texture("shadow.cascades", desc);
        for (i, (_, lists)) in plan.cascades.iter().enumerate() {
            let mut pass = graph.add_pass(&format!("shadows.cascade{i}"));
            cascades = pass.write(cascades, TextureAccess::DepthAttachment);
            let map = cascades;
            pass.execute(move |ctx| {
                let bg = self.depth_program.bind(
                    ctx.device,
                    0,
                    &[
                        ("shadow", self.views[i].as_entire_binding()),
                        ("objects", scene.objects.as_entire_binding()),
                    ],
                );
                let bg = bg?;
                let target = layer_view(ctx.texture(map), i as u32, false);
                let label = ctx.pass_id();
                self.depth32
                    .record(ctx.encoder, label, &target, true, &bg, scene, lists);
                Ok(())
            });
        }
        // The static slice writes the back map, outside the graph's pool.
        let mut static_written = None;
        if let (Some((update, lists)), Some((_, maps))) = (&plan.static_update, &self.static_maps) {
            let name = if update.target == 0 {
                "shadow.static0"
            } else {
                "shadow.static1"
            };
            let h = graph.import_texture(name, &maps[update.target]);
            let mut pass = graph.add_pass("shadows.static");
            // The back map is read in a later frame: keep the pass even unread.
            pass.side_effect();
            let h = pass.write(h, TextureAccess::DepthAttachment);
            static_written = Some((update.target, h));
            pass.execute(move |ctx| {
                let bg = self.depth_program.bind(
                    ctx.device,
                    0,
                    &[
                        ("shadow", self.views[CASCADES].as_entire_binding()),
                        ("objects", scene.objects.as_entire_binding()),
                    ],
                );
                let bg = bg?;
                let target = layer_view(ctx.texture(h), 0, false);
                let label = ctx.pass_id();
                self.depth16
                    .record(ctx.encoder, label, &target, update.clear, &bg, scene, lists);
                Ok(())
            });
        }
        let hero_map = plan.hero.as_ref().map(|(_, lists)| {
            let r = self.hero_resolution;
            let map = graph.create_texture("shadow.hero", TextureDesc::new_2d(r, r, SHADOW_FORMAT));
            let mut pass = graph.add_pass("shadows.hero");
            let map = pass.write(map, TextureAccess::DepthAttachment);
            pass.execute(move |ctx| {
                let bg = self.depth_program.bind(
                    ctx.device,
                    0,
                    &[
                        ("shadow", self.views[CASCADES + 1].as_entire_binding()),
                        ("objects", scene.objects.as_entire_binding()),
                    ],
                );
                let bg = bg?;
                let target = layer_view(ctx.texture(map), 0, false);
                let label = ctx.pass_id();
                self.depth32
                    .record(ctx.encoder, label, &target, true, &bg, scene, lists);
                Ok(())
            });
            map
        });

        let atlas_map = (!plan.projectors.is_empty()).then(|| {
            let n = self.atlas_resolution;
            let map =
                graph.create_texture("shadow.atlas", TextureDesc::new_2d(n, n, SHADOW_FORMAT));
            let mut pass = graph.add_pass("shadows.atlas");
            let map = pass.write(map, TextureAccess::DepthAttachment);
            pass.execute(move |ctx| self.record_atlas(ctx, map, scene));
            map
        });

        let mask = graph.create_texture(
            "shadow.mask",
            TextureDesc::new_2d(size.0, size.1, MASK_FORMAT),
        );
        let mut pass = graph.add_pass("shadows.mask");
        for t in [gbuffer.depth, gbuffer.frame] {
            pass.read(t, TextureAccess::Sampled);
        }
        if !plan.cascades.is_empty() {
            pass.read(cascades, TextureAccess::Sampled);
        }
        // The shown static map: this frame's slice when it just completed.
        let shown = self.static_state.shown.map(|(i, _)| i);
        let static_read = match static_written {
            Some((i, h)) if Some(i) == shown => Some(pass.read(h, TextureAccess::Sampled)),
            _ => None,
        };
        for h in [hero_map, atlas_map].into_iter().flatten() {
            pass.read(h, TextureAccess::Sampled);
        }
        let mask = pass.write(mask, TextureAccess::ColorAttachment);
        let has_cascades = !plan.cascades.is_empty();
        pass.execute(move |ctx| {
            let cascades_view = if has_cascades {
                ctx.texture(cascades)
                    .create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2Array),
                        ..Default::default()
                    })
            } else {
                layer_view(&self.placeholder, 0, true)
            };
            let static_view = match (static_read, shown, &self.static_maps) {
                (Some(h), _, _) => layer_view(ctx.texture(h), 0, true),
                (None, Some(i), Some((_, maps))) => layer_view(&maps[i], 0, true),
                _ => layer_view(&self.placeholder, 0, true),
            };
            let hero_view = match hero_map {
                Some(h) => layer_view(ctx.texture(h), 0, true),
                None => layer_view(&self.placeholder, 0, true),
            };
            let atlas_view = match atlas_map {
                Some(h) => layer_view(ctx.texture(h), 0, true),
                None => layer_view(&self.placeholder, 0, true),
            };
            let tv = wgpu::BindingResource::TextureView;
            let bg = self.mask_program.bind(
                ctx.device,
                0,
                &[
                    ("view", view.as_entire_binding()),
                    ("params", self.params.as_entire_binding()),
                    ("depth", tv(ctx.view(g_depth))),
                    ("gbuffer_frame", tv(ctx.view(g_frame))),
                    ("cascades", tv(&cascades_view)),
                    ("static_map", tv(&static_view)),
                    ("hero_map", tv(&hero_view)),
                    ("atlas", tv(&atlas_view)),
                    ("local_lights", self.local_lights.as_entire_binding()),
                    ("light_tiles", self.light_tiles.as_entire_binding()),
                    (
                        "shadow_sampler",
                        wgpu::BindingResource::Sampler(&self.sampler),
                    ),
                ],
            );
            let bg = bg?;
            let target = ctx.view(mask);
            draw_fullscreen(
                ctx,
                &self.mask,
                &bg,
                target,
                wgpu::LoadOp::Clear(wgpu::Color::WHITE),
            );
            if hero_map.is_some() {
                draw_fullscreen(ctx, &self.hero_blend, &bg, target, wgpu::LoadOp::Load);
            }
            Ok(())
        });
        Some(mask)
    }

    /// Records every projector into its atlas tile (one render pass, a viewport per tile).
    fn record_atlas(
        &self,
        ctx: &mut crate::graph::PassContext<'_>,
        map: TextureHandle,
        scene: &SceneGpu,
    ) -> Result<(), GpuError> {
        let Some(plan) = &self.plan else {
            return Ok(());
        };
        let mut groups = Vec::with_capacity(plan.projectors.len());
        for buffer in &self.atlas_views[..plan.projectors.len()] {
            let bg = self.depth_program.bind(
                ctx.device,
                0,
                &[
                    ("shadow", buffer.as_entire_binding()),
                    ("objects", scene.objects.as_entire_binding()),
                ],
            );
            let bg = bg?;
            groups.push(bg);
        }
        let target = ctx.view(map);
        let mut rp = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadows.atlas"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: target,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        scene.bind_geometry(&mut rp);
        for (p, bg) in plan.projectors.iter().zip(&groups) {
            let t = p.tile;
            rp.set_viewport(
                t.x as f32,
                t.y as f32,
                t.size as f32,
                t.size as f32,
                0.0,
                1.0,
            );
            rp.set_bind_group(0, bg, &[]);
            if !p.draws.opaque.is_empty() {
                rp.set_pipeline(&self.depth32.opaque);
                SceneGpu::draw_list(&mut rp, &p.draws.opaque);
            }
            if !p.draws.vegetation.is_empty() {
                rp.set_pipeline(&self.depth32.vegetation);
                SceneGpu::draw_list(&mut rp, &p.draws.vegetation);
            }
        }
        Ok(())
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
