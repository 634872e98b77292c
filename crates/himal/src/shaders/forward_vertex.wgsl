// The vertex stage of the forward passes over glTF surfaces (passes/forward:
// forward.wgsl, layers.wgsl). Kept apart from shaders/forward.wgsl, whose
// shading functions compute kernels import without any material bindings.
#import view
#import scene
#import gbuffer_io
#import object_vertex
#import gltf_material

struct ForwardVertexOut {
    // invariant: depth test Equal against the G-buffer must see its value
    @builtin(position) @invariant clip: vec4f,
    @location(0) normal: vec3f,
    @location(1) tangent: vec4f,
    @location(2) color: vec4f,
    @location(3) surface: vec4f,
    @location(4) world: vec3f,
    // TEXCOORD_0 in xy, TEXCOORD_1 in zw (material_uv picks per slot)
    @location(6) uv: vec4f,
}

// The vertex stage of every forward pass: the same object_vertex call as
// passes/gbuffer/textured.wgsl, so the same clip position (@invariant).
fn forward_vertex(o: Object, in: GBufferVertexIn, view: View) -> ForwardVertexOut {
    let v = object_vertex(o, in, view.view_proj, view.prev_view_proj, false, view.time.xy);
    var out: ForwardVertexOut;
    out.uv = vec4f(in.uv, in.uv1);
    out.clip = v.clip;
    out.world = v.world.xyz;
    out.normal = v.normal;
    out.tangent = gltf_world_tangent(o, v.tangent, in.tangent.w);
    out.color = in.color;
    out.surface = in.surface;
    return out;
}
