// Group 0 of the shadow depth shaders (passes/shadows/depth.wgsl and
// depth_masked.wgsl): one layout, so a depth node binds it once and draws
// with pipelines of both programs.
#import scene
// V3 impostors cast: the atlas planes at bindings 8-10 (vs_vegetation).
#import impostor_atlas
// V2: grass bends with the ripple grid (binding 12, vs_vegetation).
#import ripple

struct ShadowView {
    light_view_proj: mat4x4f,
    // x: animation time (s), as View.time.x
    time: vec4f,
}

@group(0) @binding(0) var<uniform> shadow: ShadowView;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(2) var<storage, read> instances: array<u32>;
@group(0) @binding(12) var<storage, read> ripple: Ripple;
