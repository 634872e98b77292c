//! Declare-and-bind nodes and named history on the adapter (lavapipe in CI):
//! a node whose bindings disagree with its shader fails to compile with the
//! pass and the binding named; optional inputs bind the graph's fallbacks
//! (a colour or a far-plane depth array, each only where it fits);
//! frame constants bind themselves; pass errors stop the frame; history
//! rings rotate, count valid frames, reset and report their memory.

use himal::gpu::GpuContext;
use himal::gpu::pipeline::{Program, RenderSpec, target, uniform_buffer};
use himal::gpu::testing::shared_context;
use himal::graph::{Fallback, FrameGraph, GraphError, History, Node, TextureDesc, TexturePool};

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// out = scale.x * textureLoad(src) + offset.x * (1, 1, 1, 1), from two uniforms
/// (`view` named like the frame constant) and one texture.
const BLIT: &str = r#"
#import fullscreen
struct Scale { x: vec4<f32> }
@group(0) @binding(0) var<uniform> scale: Scale;
@group(0) @binding(1) var<uniform> view: Scale;
@group(0) @binding(2) var src: texture_2d<f32>;
@group(0) @binding(3) var src_sampler: sampler;

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let s = textureSampleLevel(src, src_sampler, vec2<f32>(0.5, 0.5), 0.0);
    return scale.x.x * s + vec4<f32>(view.x.x);
}
"#;

struct Blit {
    program: Program,
    pipeline: wgpu::RenderPipeline,
    scale: wgpu::Buffer,
    view: wgpu::Buffer,
    sampler: wgpu::Sampler,
}

fn blit(ctx: &GpuContext, scale: f32, offset: f32) -> Blit {
    let program = Program::from_source(ctx, "test/blit.wgsl", BLIT).expect("program");
    let targets = [target(FORMAT)];
    let pipeline = program
        .render_pipeline(ctx, &RenderSpec::fullscreen("test.blit", &targets))
        .expect("pipeline");
    Blit {
        program,
        pipeline,
        scale: uniform_buffer(ctx, "scale", &[scale, 0.0, 0.0, 0.0]),
        view: uniform_buffer(ctx, "view", &[offset, 0.0, 0.0, 0.0]),
        sampler: ctx.device.create_sampler(&Default::default()),
    }
}

fn output(ctx: &GpuContext) -> wgpu::Texture {
    himal::gpu::texture_2d(
        &ctx.device,
        "out",
        (4, 4),
        1,
        FORMAT,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
    )
}

/// The first pixel of `t` after `graph` ran.
fn run(ctx: &GpuContext, graph: FrameGraph<'_>, t: &wgpu::Texture) -> [u8; 4] {
    himal::graph::run(ctx, graph, None, "test").expect("graph runs");
    let px = himal::gpu::read_texture(ctx, t, 0, 0).expect("read back");
    [px.bytes[0], px.bytes[1], px.bytes[2], px.bytes[3]]
}

/// The blit node into `out` with `scale` and `view` bound; `rest` binds the others.
fn blit_graph<'a>(
    b: &'a Blit,
    out: &'a wgpu::Texture,
    rest: &dyn for<'g> Fn(Node<'g, 'a>) -> Node<'g, 'a>,
) -> FrameGraph<'a> {
    let mut g = FrameGraph::new();
    let o = g.import_texture("out", out);
    let node = g
        .fullscreen("test.blit", &b.program)
        .pipeline(Ok(b.pipeline.clone()))
        .uniform("scale", &b.scale)
        .uniform("view", &b.view);
    let o = rest(node)
        .color(o, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT))
        .draw();
    g.mark_output(o);
    g
}

fn compile_error(graph: FrameGraph<'_>) -> String {
    match graph.compile() {
        Ok(_) => panic!("a node with mismatched bindings compiled"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn node_bindings_must_match_the_shader() {
    let ctx = shared_context().expect("GPU (lavapipe)");
    let b = blit(ctx, 1.0, 0.0);
    let out = output(ctx);

    fn white<'g, 'a>(n: Node<'g, 'a>) -> Node<'g, 'a> {
        n.optional("src", None, Fallback::White)
    }

    // A name the shader does not have.
    let e = compile_error(blit_graph(&b, &out, &|n| {
        white(n)
            .sampler("src_sampler", &b.sampler)
            .sampler("srcc_sampler", &b.sampler)
    }));
    assert!(
        e.contains("test.blit") && e.contains("\"srcc_sampler\""),
        "{e}"
    );
    // A binding nobody gave.
    let e = compile_error(blit_graph(&b, &out, &white));
    assert!(
        e.contains("test.blit") && e.contains("\"src_sampler\"") && e.contains("not bound"),
        "{e}"
    );
    // The wrong kind: a buffer where the shader samples a texture.
    let e = compile_error(blit_graph(&b, &out, &|n| {
        n.uniform("src", &b.scale)
            .sampler("src_sampler", &b.sampler)
    }));
    assert!(
        e.contains("\"src\"") && e.contains("a texture, given a buffer"),
        "{e}"
    );
    // Matching bindings run: white fallback x 1 + 0.
    let g = blit_graph(&b, &out, &|n| white(n).sampler("src_sampler", &b.sampler));
    assert_eq!(run(ctx, g, &out), [255; 4]);
}

#[test]
fn optional_inputs_and_frame_constants_bind_themselves() {
    let ctx = shared_context().expect("GPU (lavapipe)");
    // 0.5 x fallback + the frame constant `view` (0.25).
    let b = blit(ctx, 0.5, 0.25);
    let out = output(ctx);
    let frame_view = uniform_buffer(ctx, "frame.view", &[0.25f32, 0.0, 0.0, 0.0]);
    for (fallback, expected) in [(Fallback::White, 191), (Fallback::Black, 64)] {
        let mut g = FrameGraph::new();
        g.set_frame_constants(&[("view", &frame_view)]);
        let o = g.import_texture("out", &out);
        let o = g
            .fullscreen("test.blit", &b.program)
            .pipeline(Ok(b.pipeline.clone()))
            .uniform("scale", &b.scale)
            .optional("src", None, fallback)
            .sampler("src_sampler", &b.sampler)
            .color(o, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT))
            .draw();
        g.mark_output(o);
        let px = run(ctx, g, &out);
        // 0.5 * 1 + 0.25 = 0.75 -> 191; 0 + 0.25 -> 64 (unorm rounding).
        assert_eq!(px[0], expected, "{fallback:?}: {px:?}");
    }
    // A graph texture in place of the fallback: (0.5 * 0.2 + 0.25) -> 89.
    let src = output(ctx);
    let mut g = FrameGraph::new();
    g.set_frame_constants(&[("view", &frame_view)]);
    let s = g.import_texture("src", &src);
    let mut p = g.add_pass("test.fill");
    let s = p.write(s, himal::graph::TextureAccess::ColorAttachment);
    p.execute(move |ctx| {
        let grey = wgpu::Color {
            r: 0.2,
            g: 0.2,
            b: 0.2,
            a: 0.2,
        };
        himal::passes::common::clear_target(ctx, s, grey)
    });
    let o = g.import_texture("out", &out);
    let o = g
        .fullscreen("test.blit", &b.program)
        .pipeline(Ok(b.pipeline.clone()))
        .uniform("scale", &b.scale)
        .optional("src", Some(s), Fallback::Black)
        .sampler("src_sampler", &b.sampler)
        .color(o, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT))
        .draw();
    g.mark_output(o);
    let px = run(ctx, g, &out);
    assert_eq!(px[0], 89, "{px:?}");
}

/// Shadow-map style: out = comparison of 0.5 against `map` (a depth array).
const SHADOW: &str = r#"
#import fullscreen
@group(0) @binding(0) var map: texture_depth_2d_array;
@group(0) @binding(1) var cmp: sampler_comparison;

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSampleCompareLevel(map, cmp, vec2<f32>(0.5, 0.5), 0, 0.5));
}
"#;

#[test]
fn an_absent_shadow_map_binds_the_far_plane_and_fallbacks_must_fit() {
    let ctx = shared_context().expect("GPU (lavapipe)");
    let program = Program::from_source(ctx, "test/shadow.wgsl", SHADOW).expect("program");
    let targets = [target(FORMAT)];
    let pipeline = program
        .render_pipeline(ctx, &RenderSpec::fullscreen("test.shadow", &targets))
        .expect("pipeline");
    let cmp = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        compare: Some(wgpu::CompareFunction::LessEqual),
        ..Default::default()
    });
    let out = output(ctx);
    let graph = |fallback| {
        let mut g = FrameGraph::new();
        let o = g.import_texture("out", &out);
        let o = g
            .fullscreen("test.shadow", &program)
            .pipeline(Ok(pipeline.clone()))
            .optional_array("map", None, fallback)
            .sampler("cmp", &cmp)
            .color(o, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT))
            .draw();
        g.mark_output(o);
        g
    };
    // 0.5 <= 1.0 (the far plane): fully lit.
    assert_eq!(run(ctx, graph(Fallback::DepthFar), &out), [255; 4]);
    // A colour fallback where the shader reads a depth array is refused by name.
    let e = compile_error(graph(Fallback::White));
    assert!(
        e.contains("test.shadow") && e.contains("\"map\"") && e.contains("colour fallback"),
        "{e}"
    );
    // And the depth fallback where the shader samples a colour texture.
    let b = blit(ctx, 1.0, 0.0);
    let e = compile_error(blit_graph(&b, &out, &|n| {
        n.optional("src", None, Fallback::DepthFar)
            .sampler("src_sampler", &b.sampler)
    }));
    assert!(
        e.contains("\"src\"") && e.contains("depth-array fallback"),
        "{e}"
    );
}

#[test]
fn a_pass_error_stops_the_frame_and_names_the_pass() {
    let ctx = shared_context().expect("GPU (lavapipe)");
    let out = output(ctx);
    let mut g = FrameGraph::new();
    let o = g.import_texture("out", &out);
    let mut p = g.add_pass("test.failing");
    let o = p.write(o, himal::graph::TextureAccess::ColorAttachment);
    p.execute(|_| {
        Err(himal::gpu::GpuError::Other(
            "no pipeline for this key".into(),
        ))
    });
    g.mark_output(o);
    let compiled = g.compile().expect("compiles");
    match compiled.execute(&ctx.device, &mut TexturePool::new(), None) {
        Err(GraphError::Pass { pass, message }) => {
            assert_eq!(pass, "test.failing");
            assert!(message.contains("no pipeline"), "{message}");
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a failing pass recorded a frame"),
    }
}

#[test]
fn history_rings_rotate_count_and_reset() {
    let ctx = shared_context().expect("GPU (lavapipe)");
    let mut h = History::new();
    let desc = TextureDesc::new_2d(8, 4, FORMAT);
    h.declare(&ctx.device, "test.ring", &desc, 3);
    assert_eq!(h.frames("test.ring"), 0);
    // By identity (wgpu compares textures by id): their Debug text also
    // shows the error sink's lock state, which other tests' threads change.
    let id = |t: Option<&wgpu::Texture>| t.expect("declared").clone();
    let mut seen: Vec<wgpu::Texture> = Vec::new();
    for frame in 1..=4u32 {
        let next = id(h.texture("test.ring", 0));
        let before = id(h.texture("test.ring", 1));
        if !seen.contains(&next) {
            seen.push(next.clone());
        }
        let mut g = FrameGraph::new();
        let ring = h.import(&mut g, "test.ring").expect("declared");
        assert_eq!(ring.frames, frame - 1);
        assert_ne!(ring.previous[0], ring.previous[1]);
        drop(g);
        h.swap();
        assert_eq!(h.frames("test.ring"), frame);
        // What was written is now one frame ago, and the frame before two.
        assert_eq!(id(h.texture("test.ring", 1)), next);
        assert_eq!(id(h.texture("test.ring", 2)), before);
    }
    assert_eq!(seen.len(), 3, "the ring cycles through its three textures");
    // A frame that does not import the ring loses its history.
    h.swap();
    assert_eq!(h.frames("test.ring"), 0);
    let mut g = FrameGraph::new();
    h.import(&mut g, "test.ring");
    drop(g);
    h.swap();
    assert_eq!(h.frames("test.ring"), 1);
    h.reset();
    assert_eq!(h.frames("test.ring"), 0);
    // A new size recreates it; memory is three 8x4 RGBA8 textures.
    assert_eq!(h.memory(), vec![("test.ring".to_string(), 3 * 8 * 4 * 4)]);
    h.declare(
        &ctx.device,
        "test.ring",
        &TextureDesc::new_2d(16, 4, FORMAT),
        3,
    );
    assert!(h.has("test.ring", (16, 4)));
    assert_eq!(h.memory()[0].1, 3 * 16 * 4 * 4);
    assert!(h.import(&mut FrameGraph::new(), "missing").is_none());
}
