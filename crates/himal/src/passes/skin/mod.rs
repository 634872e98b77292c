//! `skin`: the scene's skinned and morphed meshes deformed on the GPU each
//! frame, morph targets first, then joints (the joint matrices and morph
//! weights come from `SceneGpu::update_objects`), then `skin.copy`
//! puts them into the scene's vertex buffer, before any pass draws it.
//! Every later pass (G-buffer, shadows, sky occlusion) draws the pose
//! unchanged. CPU twin: [`reference::skin`]. docs/gltf.md, "Animation and
//! skinning".

pub mod reference;

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::SceneGpu;
use crate::graph::{BufferAccess, FrameGraph};

/// Threads per workgroup of `skin.wgsl`.
const GROUP: u32 = 64;

/// The skinning pipeline (one compute entry point).
pub struct SkinPass {
    program: Program,
    pipeline: wgpu::ComputePipeline,
}

impl SkinPass {
    /// Compiles `skin.wgsl`.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/skin/skin.wgsl")?;
        let pipeline = program.compute_pipeline(
            ctx,
            "cs_main",
            &[("VERTEX_FLOATS", (VERTEX_BYTES / 4) as f64)],
        )?;
        Ok(Self { program, pipeline })
    }

    /// Adds `skin` and `skin.copy` when `scene` has skinned meshes.
    pub fn add<'a>(&'a self, graph: &mut FrameGraph<'a>, scene: &'a SceneGpu) {
        let Some(skins) = &scene.skins else {
            return;
        };
        let skinned = graph.import_buffer("skin.skinned", &skins.skinned);
        let skinned = graph
            .compute("skin", &self.program)
            .compute_pipeline(Ok(self.pipeline.clone()))
            .uniform("params", &skins.params)
            .uniform("sources", &skins.sources)
            .uniform("joints", &skins.joints)
            .uniform("prev_joints", &skins.prev_joints)
            .uniform("prev", &scene.deform)
            .uniform("morph", &skins.morph)
            .uniform("weights", &skins.weights)
            .write_buffer("skinned", skinned)
            .dispatch([skins.vertex_count.div_ceil(GROUP), 1, 1])
            .buffer(skinned);
        let vertices = graph.import_buffer("scene.vertices", &scene.vertices);
        let mut copy = graph.add_pass("skin.copy");
        let src = copy.read_buffer(skinned, BufferAccess::CopySrc);
        let dst = copy.write_buffer(vertices, BufferAccess::CopyDst);
        // The draws read the vertex buffer outside the graph.
        copy.side_effect();
        let (offset, bytes) = (
            skins.first_vertex as u64 * VERTEX_BYTES,
            skins.vertex_count as u64 * VERTEX_BYTES,
        );
        copy.execute(move |pc| {
            let (src, dst) = (pc.buffer(src), pc.buffer(dst));
            pc.encoder.copy_buffer_to_buffer(src, 0, dst, offset, bytes);
            Ok(())
        });
    }
}

const VERTEX_BYTES: u64 = std::mem::size_of::<crate::scene::Vertex>() as u64;
