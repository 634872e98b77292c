//! The shadow passes as frame-graph nodes: cascades, static slice, hero,
//! atlas, the mask, and the debug view (planned by `ShadowPass::update`).

use super::*;
use crate::graph::{BufferAccess, BufferDesc, Fallback};
use crate::passes::cull::{Culled, bind_instances};

/// Edge of a mask tile in pixels (`SHADOW_TILE` in shaders/shadow.wgsl).
const TILE: u32 = 16;

/// One sun view's depth node: `lists` (and, with `culled`, the GPU list
/// they name) into layer `target.1` of `target.0` (cleared to the far
/// plane first when `target.2`), seen through `ShadowPass::views[view]`.
/// `keep`: never culled by the graph (read by a later frame).
struct DepthNode<'s, 'a> {
    id: &'s str,
    view: &'a wgpu::Buffer,
    target: (TextureHandle, u32, bool),
    pipelines: &'a DepthPipelines,
    lists: &'a DrawLists,
    culled: Option<Culled<'a>>,
    keep: bool,
    /// Draw inside this texel rectangle (a static tile), cleared first
    /// when `clear_rect`.
    rect: Option<[u32; 4]>,
    clear_rect: bool,
    /// Which casters it draws.
    part: super::depth::Part,
}
use crate::passes::common::view_node;

/// The sun's shadow textures of one frame.
#[derive(Clone, Copy, Debug)]
pub struct SunMaps {
    /// The shadow mask (R sun, GBA local lights).
    pub mask: Option<TextureHandle>,
    /// The cascades (depth array), when any was rendered.
    pub cascades: Option<TextureHandle>,
    /// The static map shown (S2), when there is one.
    pub static_map: Option<TextureHandle>,
    /// The local lights' atlas (S3), when any projector was rendered
    /// (particles read it; the mask has it in its channels).
    pub atlas: Option<TextureHandle>,
}

/// Graph names of the two static maps.
const STATIC_NAMES: [&str; 2] = ["shadow.static0", "shadow.static1"];

impl ShadowPass {
    /// Adds the shadow nodes; returns the mask and the sun's maps it
    /// rendered or reads (E4 particles look them up themselves), or `None`
    /// when shadows are off (no plan this frame). `view` is the frame
    /// constant. `culled`: the GPU-culled lists the cascades draw (V6).
    pub fn add_maps<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        gbuffer: GBuffer,
        scene: &'a SceneGpu,
        culled: Option<Culled<'a>>,
        extra: Option<&'a dyn CascadeCaster>,
    ) -> Option<SunMaps> {
        let plan = self.plan.as_ref()?;
        let n = self.cascade_resolution;
        let mut desc = TextureDesc::new_2d(n, n, SHADOW_FORMAT);
        desc.depth_or_layers = CASCADES as u32;
        let mut cascades = graph.create_texture("shadow.cascades", desc);
        // Vegetation casts in passes of its own (bench rows
        // `vegetation.shadow*`, issue #18), after each cascade's opaque casters.
        let vegetation = scene.has_vegetation();
        let parts: &[(&str, super::depth::Part)] = match vegetation {
            true => &[
                ("shadows.cascade", super::depth::Part::Opaque),
                ("vegetation.shadow", super::depth::Part::Vegetation),
            ],
            false => &[("shadows.cascade", super::depth::Part::All)],
        };
        for (i, (_, lists)) in plan.cascades.iter().enumerate() {
            for (k, &(name, part)) in parts.iter().enumerate() {
                let id = format!("{name}{i}");
                let node = DepthNode {
                    id: &id,
                    view: &self.views[i],
                    target: (cascades, i as u32, k == 0),
                    pipelines: &self.depth32,
                    lists,
                    culled,
                    keep: false,
                    rect: None,
                    clear_rect: false,
                    part,
                };
                cascades = self.depth_node(graph, scene, node);
            }
            if let Some(c) = extra {
                cascades = c.add_cascade(graph, cascades, i as u32, &self.views[i]);
            }
        }
        let cascades = (!plan.cascades.is_empty()).then_some(cascades);
        // The static slice writes the back map, outside the graph's pool.
        // Each map's latest version this frame (imported once).
        let mut static_written: [Option<TextureHandle>; 2] = [None, None];
        if let (Some((update, lists)), Some((_, maps))) = (&plan.static_update, &self.static_maps) {
            let t = update.target.min(1);
            let h = graph.import_texture(STATIC_NAMES[t], &maps[t]);
            let target = (h, 0, update.clear);
            let depth16 = &self.depth16;
            // The back map is read in a later frame: keep the pass even unread.
            let node = DepthNode {
                id: "shadows.static",
                view: &self.views[CASCADES],
                target,
                pipelines: depth16,
                lists,
                culled: None,
                keep: true,
                rect: None,
                clear_rect: false,
                part: super::depth::Part::All,
            };
            let h = self.depth_node(graph, scene, node);
            static_written[update.target.min(1)] = Some(h);
        }
        // The world's static tiles: scene objects, pool instances, terrain.
        let first_terrain_view = plan.cascades.len();
        for (k, tile) in plan.static_tiles.iter().enumerate() {
            let Some((_, maps)) = &self.static_maps else {
                break;
            };
            let (target, rect) = (tile.update.target.min(1), tile.update.rect);
            let mut h = match static_written[target] {
                Some(h) => h,
                None => graph.import_texture(STATIC_NAMES[target], &maps[target]),
            };
            let view = &self.tile_views[k.min(MAX_STATIC_TILES - 1)];
            // Each tile's nodes are kept: the map is read in later frames.
            let objects = format!("shadows.static.tile{k}");
            let pool = format!("shadows.static.pool{k}");
            let mut steps = vec![(&objects, &tile.objects, None, true)];
            if culled.is_some() && tile.pool.pool_view.is_some() {
                steps.push((&pool, &tile.pool, culled, false));
            }
            for (id, lists, culled, clear) in steps {
                let node = DepthNode {
                    id,
                    view,
                    target: (h, 0, false),
                    pipelines: &self.depth16,
                    lists,
                    culled,
                    keep: true,
                    rect: Some(rect),
                    clear_rect: clear,
                    part: super::depth::Part::All,
                };
                h = self.depth_node(graph, scene, node);
            }
            if let Some(c) = extra {
                h = c.add_static_tile(graph, h, first_terrain_view + k, view, rect);
            }
            static_written[target] = Some(h);
        }
        let hero_map = plan.hero.as_ref().map(|(_, lists)| {
            let r = self.hero_resolution;
            let map = graph.create_texture("shadow.hero", TextureDesc::new_2d(r, r, SHADOW_FORMAT));
            let target = (map, 0, true);
            let depth32 = &self.depth32;
            let node = DepthNode {
                id: "shadows.hero",
                view: &self.views[CASCADES + 1],
                target,
                pipelines: depth32,
                lists,
                culled: None,
                keep: false,
                rect: None,
                clear_rect: false,
                part: super::depth::Part::All,
            };
            self.depth_node(graph, scene, node)
        });
        let atlas_map = (!plan.projectors.is_empty()).then(|| self.add_atlas(graph, scene, plan));
        // The shown static map: this frame's slice when it just completed,
        // else the front map of an earlier frame.
        let shown = match self.world {
            Some(_) => self.tiled.shown.map(|(i, _, _)| i),
            None => self.static_state.shown.map(|(i, _)| i),
        };
        let static_map = match (shown, &self.static_maps) {
            (Some(s), Some((_, maps))) => {
                let s = s.min(1);
                Some(
                    static_written[s]
                        .unwrap_or_else(|| graph.import_texture(STATIC_NAMES[s], &maps[s])),
                )
            }
            _ => None,
        };
        let mask = graph.create_texture(
            "shadow.mask",
            TextureDesc::new_2d(size.0, size.1, MASK_FORMAT),
        );
        // The hero pass's scissor: everywhere, or its box's rectangle
        // (`hero_screen_rect`), or nothing when that is off screen.
        let hero = match (hero_map.is_some(), plan.hero_rect) {
            (false, _) => None,
            (true, None) => Some([0, 0, size.0, size.1]),
            (true, Some(r)) => r.and_then(|r| ndc_scissor(r, size)),
        };
        let far = Fallback::DepthFar;
        // #23: each tile's state per map (one vec4u a tile), then the mask.
        let tiles = plan.mask_tiles.then(|| {
            let n = size.0.div_ceil(TILE) as u64 * size.1.div_ceil(TILE) as u64;
            let states = graph.create_buffer("shadow.mask_tiles", BufferDesc::new(16 * n));
            graph
                .compute("shadows.mask_tiles", &self.tiles_program)
                .compute_pipeline(Ok(self.tiles.clone()))
                .uniform("params", &self.params)
                .read("depth", gbuffer.depth)
                .read("gbuffer_frame", gbuffer.frame)
                .optional_array("cascades", cascades, far)
                .optional_array("static_map", static_map, far)
                .optional_array("atlas", atlas_map, far)
                .uniform("local_lights", &self.local_lights)
                .uniform("light_tiles", &self.light_tiles)
                .write_buffer("tile_states", states)
                .dispatch([size.0.div_ceil(TILE), size.1.div_ceil(TILE), 1])
                .buffer(states)
        });
        let mask_pipeline = if tiles.is_some() {
            &self.mask_tiled
        } else {
            &self.mask
        };
        let node = graph
            .raster("shadows.mask", &self.mask_program)
            .pipeline(Ok(mask_pipeline.clone()));
        let node = match tiles {
            Some(h) => node.read_buffer("tile_states", h, BufferAccess::StorageRead),
            None => node.optional_buffer("tile_states", None),
        };
        let written = node
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
                if let Some([x, y, w, h]) = hero {
                    rp.set_pipeline(&self.hero_blend);
                    rp.set_scissor_rect(x, y, w, h);
                    rp.draw(0..3, 0..1);
                }
                Ok(())
            });
        Some(SunMaps {
            mask: written.colors.first().copied(),
            cascades,
            static_map,
            atlas: atlas_map,
        })
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
            rect,
            clear_rect,
            part,
        } = node;
        let culled = culled.filter(|_| lists.gpu_view.is_some() || lists.pool_view.is_some());
        let alpha_test = self.plan.as_ref().is_some_and(|p| p.alpha_test);
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
            .uniform("shadow", view)
            .uniform("objects", &scene.objects)
            .uniform("ripple", &scene.ripple)
            .external("impostor_color_load", &scene.impostor_atlas.color)
            .external("impostor_normal_load", &scene.impostor_atlas.normal)
            .external("impostor_depth_load", &scene.impostor_atlas.depth);
        let mut node = bind_instances(node, culled.as_ref(), &scene.instances).depth(
            map,
            Some(layer_view_desc(layer)),
            ops,
        );
        if keep {
            node = node.side_effect();
        }
        node.record(move |ctx, rp| {
            match rect {
                Some(r) if clear_rect => pipelines.clear_rect(rp, r),
                Some(r) => super::depth::set_rect(rp, r),
                None => {}
            }
            let device = (ctx.device, alpha_test);
            let culled = culled.as_ref().map(|c| (c, ctx));
            pipelines.draw_culled(rp, scene, lists, culled, device, part)
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
                            ("ripple", scene.ripple.as_entire_binding()),
                            ("instances", scene.instances.as_entire_binding()),
                            (
                                "impostor_color_load",
                                wgpu::BindingResource::TextureView(&scene.impostor_atlas.color),
                            ),
                            (
                                "impostor_normal_load",
                                wgpu::BindingResource::TextureView(&scene.impostor_atlas.normal),
                            ),
                            (
                                "impostor_depth_load",
                                wgpu::BindingResource::TextureView(&scene.impostor_atlas.depth),
                            ),
                        ],
                    )?;
                    let t = p.tile;
                    let (x, y, edge) = (t.x as f32, t.y as f32, t.size as f32);
                    rp.set_viewport(x, y, edge, edge, 0.0, 1.0);
                    rp.set_bind_group(0, &bg, &[]);
                    self.depth32.draw_pipelines(
                        rp,
                        scene,
                        &p.draws,
                        (ctx.device, plan.alpha_test),
                        super::depth::Part::All,
                    )?;
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
