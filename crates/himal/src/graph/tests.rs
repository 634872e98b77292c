//! Device-free tests of building and compiling graphs.

use super::*;
use wgpu::TextureFormat as F;

fn desc(format: F) -> TextureDesc {
    TextureDesc::new_2d(64, 32, format)
}

fn ids<'g>(g: &'g CompiledGraph<'_>) -> Vec<&'g str> {
    g.passes().iter().map(|p| p.id.as_str()).collect()
}

/// a -> (b, c) -> d -> imported output.
#[test]
fn diamond_orders_producers_first() {
    let mut g = FrameGraph::new();
    let x = g.create_texture("x", desc(F::Rgba16Float));
    let y = g.create_texture("y", desc(F::Rgba16Float));
    let z = g.create_texture("z", desc(F::Rgba16Float));
    let out = g.import_texture_desc("out", desc(F::Rgba8Unorm));
    g.mark_output(out);
    // Declared out of the obvious order to show the sort is by dependency
    // only where needed: declaration order is kept when valid.
    let mut a = g.add_pass("a");
    let x1 = a.write(x, TextureAccess::ColorAttachment);
    a.execute(|_| Ok(()));
    let mut c = g.add_pass("c");
    c.read(x1, TextureAccess::Sampled);
    let z1 = c.write(z, TextureAccess::StorageWrite);
    c.execute(|_| Ok(()));
    let mut b = g.add_pass("b");
    b.read(x1, TextureAccess::Sampled);
    let y1 = b.write(y, TextureAccess::ColorAttachment);
    b.execute(|_| Ok(()));
    let mut d = g.add_pass("d");
    d.read(y1, TextureAccess::Sampled);
    d.read(z1, TextureAccess::Sampled);
    d.write(out, TextureAccess::ColorAttachment);
    d.execute(|_| Ok(()));
    let g = g.compile().expect("valid diamond");
    assert_eq!(ids(&g), ["a", "c", "b", "d"]);
    assert!(g.culled().is_empty());
    assert_eq!(g.passes()[3].reads.len(), 2);
    assert_eq!(g.passes()[3].writes[0].version, 1);
}

/// A pass reading an old version runs before the pass that overwrites it.
#[test]
fn reader_of_old_version_runs_before_overwrite() {
    let mut g = FrameGraph::new();
    let t = g.import_texture_desc("hdr", desc(F::Rgba16Float));
    let copy = g.import_texture_desc("copy", desc(F::Rgba16Float));
    g.mark_output(t);
    g.mark_output(copy);
    let mut a = g.add_pass("light");
    let t1 = a.write(t, TextureAccess::ColorAttachment);
    a.execute(|_| Ok(()));
    let mut b = g.add_pass("sky");
    b.write(t1, TextureAccess::ColorAttachment);
    b.execute(|_| Ok(()));
    let mut c = g.add_pass("snapshot");
    c.read(t1, TextureAccess::CopySrc);
    c.write(copy, TextureAccess::CopyDst);
    c.execute(|_| Ok(()));
    let g = g.compile().expect("reorderable");
    assert_eq!(ids(&g), ["light", "snapshot", "sky"]);
}

#[test]
fn reading_overwritten_version_after_depending_on_overwrite_is_a_cycle() {
    let mut g = FrameGraph::new();
    let t = g.import_texture_desc("hdr", desc(F::Rgba16Float));
    let s = g.create_texture("s", desc(F::Rgba16Float));
    let mut a = g.add_pass("a");
    let t1 = a.write(t, TextureAccess::ColorAttachment);
    a.execute(|_| Ok(()));
    let mut b = g.add_pass("b");
    b.write(t1, TextureAccess::ColorAttachment);
    let s1 = b.write(s, TextureAccess::ColorAttachment);
    b.execute(|_| Ok(()));
    let mut c = g.add_pass("c");
    c.read(t1, TextureAccess::Sampled);
    c.read(s1, TextureAccess::Sampled);
    c.side_effect();
    c.execute(|_| Ok(()));
    match g.compile() {
        Err(GraphError::Cycle(p)) => assert_eq!(p, ["b", "c"]),
        other => panic!("expected Cycle, got {:?}", other.map(|g| ids(&g).join(","))),
    }
}

fn dead_branch_graph(keep_dead: bool) -> Vec<String> {
    let mut g = FrameGraph::new();
    let x = g.create_texture("x", desc(F::Rgba16Float));
    let dead = g.create_texture("dead", desc(F::Rgba16Float));
    let out = g.import_texture_desc("out", desc(F::Rgba8Unorm));
    g.mark_output(out);
    let mut a = g.add_pass("a");
    let x1 = a.write(x, TextureAccess::ColorAttachment);
    a.execute(|_| Ok(()));
    let mut b = g.add_pass("debug.dead");
    b.read(x1, TextureAccess::Sampled);
    let dead1 = b.write(dead, TextureAccess::ColorAttachment);
    b.execute(|_| Ok(()));
    let mut c = g.add_pass("c");
    c.read(x1, TextureAccess::Sampled);
    c.write(out, TextureAccess::ColorAttachment);
    c.execute(|_| Ok(()));
    if keep_dead {
        g.mark_output(dead1);
    }
    let g = g.compile().expect("valid");
    assert_eq!(g.passes().len() + g.culled().len(), 3);
    if !keep_dead {
        // Culled accesses derive no usages and allocate nothing.
        assert_eq!(g.texture_usages("dead"), Some(wgpu::TextureUsages::empty()));
        assert_eq!(g.pool_plan().texture_slot("dead"), None);
    }
    g.culled().to_vec()
}

#[test]
fn dead_branch_is_culled_unless_marked_output() {
    assert_eq!(dead_branch_graph(false), ["debug.dead"]);
    assert!(dead_branch_graph(true).is_empty());
}

#[test]
fn nothing_reaches_an_output_culls_everything() {
    let mut g = FrameGraph::new();
    let x = g.create_texture("x", desc(F::Rgba16Float));
    let mut a = g.add_pass("a");
    a.write(x, TextureAccess::ColorAttachment);
    a.execute(|_| Ok(()));
    let g = g.compile().expect("valid");
    assert!(g.passes().is_empty());
    assert_eq!(g.culled(), ["a"]);
}

#[test]
fn side_effect_pass_and_its_inputs_are_kept() {
    let mut g = FrameGraph::new();
    let lum = g.create_buffer("lum", BufferDesc::new(256));
    let mut a = g.add_pass("lum.reduce");
    let lum1 = a.write_buffer(lum, BufferAccess::StorageWrite);
    a.execute(|_| Ok(()));
    let mut b = g.add_pass("lum.readback");
    b.read_buffer(lum1, BufferAccess::CopySrc);
    b.side_effect();
    b.execute(|_| Ok(()));
    let mut c = g.add_pass("unused");
    c.read_buffer(lum1, BufferAccess::Uniform);
    c.execute(|_| Ok(()));
    let g = g.compile().expect("valid");
    assert_eq!(ids(&g), ["lum.reduce", "lum.readback"]);
    assert_eq!(g.culled(), ["unused"]);
    assert!(g.passes()[1].side_effect);
    // Uniform came only from the culled pass.
    let u = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    assert_eq!(g.buffer_usages("lum"), Some(u));
}

#[test]
fn usages_are_the_union_of_live_accesses() {
    let mut g = FrameGraph::new();
    let t = g.create_texture("t", desc(F::Rgba8Unorm));
    let mut a = g.add_pass("draw");
    let t1 = a.write(t, TextureAccess::ColorAttachment);
    a.execute(|_| Ok(()));
    let mut b = g.add_pass("sample");
    b.read(t1, TextureAccess::Sampled);
    b.side_effect();
    b.execute(|_| Ok(()));
    let mut c = g.add_pass("copy");
    c.read(t1, TextureAccess::CopySrc);
    c.side_effect();
    c.execute(|_| Ok(()));
    let g = g.compile().expect("valid");
    use wgpu::TextureUsages as U;
    let want = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
    assert_eq!(g.texture_usages("t"), Some(want));
    assert_eq!(g.texture_usages("missing"), None);
}

#[test]
fn buffer_usages_and_extra_usages() {
    let mut g = FrameGraph::new();
    let mut d = BufferDesc::new(64);
    d.extra_usages = wgpu::BufferUsages::COPY_DST;
    let args = g.create_buffer("args", d);
    let mut a = g.add_pass("cull");
    let args1 = a.write_buffer(args, BufferAccess::StorageWrite);
    a.execute(|_| Ok(()));
    let mut b = g.add_pass("draw");
    b.read_buffer(args1, BufferAccess::Indirect);
    b.read_buffer(args1, BufferAccess::Uniform);
    b.side_effect();
    b.execute(|_| Ok(()));
    let g = g.compile().expect("valid");
    use wgpu::BufferUsages as U;
    let want = U::STORAGE | U::INDIRECT | U::UNIFORM | U::COPY_DST;
    assert_eq!(g.buffer_usages("args"), Some(want));
    assert_eq!(g.texture_usages("args"), None);
}

#[test]
fn read_before_write_is_an_error() {
    let mut g = FrameGraph::new();
    let t = g.create_texture("t", desc(F::Rgba8Unorm));
    let mut a = g.add_pass("a");
    a.read(t, TextureAccess::Sampled);
    a.side_effect();
    a.execute(|_| Ok(()));
    let err = g.compile().err();
    let want = GraphError::ReadBeforeWrite {
        pass: "a".into(),
        resource: "t".into(),
    };
    assert_eq!(err, Some(want));
}

#[test]
fn imported_version_zero_counts_as_written() {
    let mut g = FrameGraph::new();
    let h = g.import_texture_desc("history.depth", desc(F::Depth32Float));
    let mut a = g.add_pass("a");
    a.read(h, TextureAccess::Sampled);
    a.side_effect();
    a.execute(|_| Ok(()));
    assert!(g.compile().is_ok());
}

#[test]
fn two_writers_of_one_version_is_stale() {
    let mut g = FrameGraph::new();
    let t = g.import_texture_desc("t", desc(F::Rgba8Unorm));
    let mut a = g.add_pass("a");
    a.write(t, TextureAccess::ColorAttachment);
    a.execute(|_| Ok(()));
    let mut b = g.add_pass("b");
    b.write(t, TextureAccess::ColorAttachment);
    b.execute(|_| Ok(()));
    let want = GraphError::StaleVersion {
        pass: "b".into(),
        resource: "t".into(),
        used: 0,
        latest: 1,
    };
    assert_eq!(g.compile().err(), Some(want));
}

#[test]
fn duplicate_pass_and_missing_execute() {
    let mut g = FrameGraph::new();
    g.add_pass("ao.hbao").execute(|_| Ok(()));
    g.add_pass("ao.hbao").execute(|_| Ok(()));
    assert_eq!(
        g.compile().err(),
        Some(GraphError::DuplicatePass("ao.hbao".into()))
    );

    let mut g = FrameGraph::new();
    g.add_pass("ao.hbao").side_effect();
    assert_eq!(
        g.compile().err(),
        Some(GraphError::MissingExecute("ao.hbao".into()))
    );
}

#[test]
fn foreign_handles_wrong_access_and_duplicate_names_are_errors() {
    let mut other = FrameGraph::new();
    let foreign = other.create_texture("t", desc(F::Rgba8Unorm));
    let mut g = FrameGraph::new();
    let mut a = g.add_pass("a");
    a.read(foreign, TextureAccess::Sampled);
    a.execute(|_| Ok(()));
    let want = GraphError::UnknownHandle {
        context: "a".into(),
    };
    assert_eq!(g.compile().err(), Some(want));

    let mut g = FrameGraph::new();
    let t = g.create_texture("t", desc(F::Rgba8Unorm));
    let mut a = g.add_pass("a");
    a.write(t, TextureAccess::Sampled);
    a.execute(|_| Ok(()));
    assert!(matches!(
        g.compile(),
        Err(GraphError::InvalidAccess {
            declared_with: "write",
            ..
        })
    ));

    let mut g = FrameGraph::new();
    g.create_texture("t", desc(F::Rgba8Unorm));
    g.create_buffer("t", BufferDesc::new(4));
    assert_eq!(
        g.compile().err(),
        Some(GraphError::DuplicateResource("t".into()))
    );
}

/// Two transients with disjoint lifetimes and one description share a slot;
/// overlapping or differently described ones do not.
#[test]
fn pool_plan_reuses_slots_after_last_use() {
    let mut g = FrameGraph::new();
    let a = g.create_texture("a", desc(F::Rgba16Float));
    let b = g.create_texture("b", desc(F::Rgba16Float));
    let c = g.create_texture("c", desc(F::Rgba16Float));
    let half = g.create_texture("half", TextureDesc::new_2d(32, 16, F::Rgba16Float));
    let out = g.import_texture_desc("out", desc(F::Rgba16Float));
    g.mark_output(out);
    let mut p = g.add_pass("p0");
    let a1 = p.write(a, TextureAccess::ColorAttachment);
    p.execute(|_| Ok(()));
    let mut p = g.add_pass("p1");
    p.read(a1, TextureAccess::Sampled);
    let b1 = p.write(b, TextureAccess::ColorAttachment);
    p.execute(|_| Ok(()));
    // a is dead after p1: c (same key) takes its slot; b overlaps c.
    let mut p = g.add_pass("p2");
    p.read(b1, TextureAccess::Sampled);
    let c1 = p.write(c, TextureAccess::ColorAttachment);
    let h1 = p.write(half, TextureAccess::ColorAttachment);
    p.execute(|_| Ok(()));
    let mut p = g.add_pass("p3");
    p.read(c1, TextureAccess::Sampled);
    p.read(h1, TextureAccess::Sampled);
    p.write(out, TextureAccess::ColorAttachment);
    p.execute(|_| Ok(()));
    let g = g.compile().expect("valid");
    let plan = g.pool_plan();
    let slot = |n: &str| plan.texture_slot(n).expect("planned");
    assert_eq!(slot("a"), slot("c"));
    assert_ne!(slot("a"), slot("b"));
    assert_ne!(slot("half"), slot("a"));
    assert_ne!(slot("half"), slot("b"));
    assert_eq!(plan.texture_slots.len(), 3);
    assert_eq!(plan.texture_slot("out"), None); // imported: not pooled
    let a = plan.textures.iter().find(|x| x.resource == "a").expect("a");
    assert_eq!((a.first_pass, a.last_pass), (0, 1));
}

#[test]
fn transient_output_keeps_its_slot_to_the_end() {
    let mut g = FrameGraph::new();
    let a = g.create_texture("debug.a", desc(F::Rgba8Unorm));
    let b = g.create_texture("b", desc(F::Rgba8Unorm));
    let mut p = g.add_pass("p0");
    let a1 = p.write(a, TextureAccess::ColorAttachment);
    p.execute(|_| Ok(()));
    g.mark_output(a1);
    let mut p = g.add_pass("p1");
    p.write(b, TextureAccess::ColorAttachment);
    p.side_effect();
    p.execute(|_| Ok(()));
    let g = g.compile().expect("valid");
    let plan = g.pool_plan();
    assert_ne!(plan.texture_slot("debug.a"), plan.texture_slot("b"));
}

#[test]
fn describe_lists_passes_accesses_and_usages() {
    let mut g = FrameGraph::new();
    let albedo = g.create_texture("gbuffer.albedo", desc(F::Rgba8UnormSrgb));
    let depth = g.create_texture("depth", desc(F::Depth32Float));
    let hdr = g.import_texture_desc("hdr", desc(F::Rgba16Float));
    g.mark_output(hdr);
    let mut p = g.add_pass("gbuffer");
    let albedo1 = p.write(albedo, TextureAccess::ColorAttachment);
    let depth1 = p.write(depth, TextureAccess::DepthAttachment);
    p.execute(|_| Ok(()));
    let mut p = g.add_pass("lighting");
    p.read(albedo1, TextureAccess::Sampled);
    p.read(depth1, TextureAccess::DepthRead);
    p.write(hdr, TextureAccess::ColorAttachment);
    p.execute(|_| Ok(()));
    let mut p = g.add_pass("debug.unused");
    p.read(depth1, TextureAccess::Sampled);
    p.execute(|_| Ok(()));
    let text = g.compile().expect("valid").describe();
    for needle in [
        "1. gbuffer",
        "writes gbuffer.albedo@1 (ColorAttachment), depth@1 (DepthAttachment)",
        "2. lighting",
        "reads gbuffer.albedo@1 (Sampled), depth@1 (DepthRead)",
        "writes hdr@1 (ColorAttachment)",
        "culled: debug.unused",
        "TEXTURE_BINDING | RENDER_ATTACHMENT",
        "[output]",
    ] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
}

#[test]
fn texture_byte_size_counts_mips() {
    let mut d = TextureDesc::new_2d(64, 64, F::Rgba16Float);
    assert_eq!(d.byte_size(), 64 * 64 * 8);
    d.mip_levels = 7; // 64 .. 1: 4096 + 1024 + 256 + 64 + 16 + 4 + 1 texels
    assert_eq!(d.byte_size(), 5461 * 8);
    assert_eq!(TextureDesc::new_2d(4, 4, F::Depth32Float).byte_size(), 64);
}
