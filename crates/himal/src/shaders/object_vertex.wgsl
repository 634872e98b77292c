// The object vertex stage of every pass that draws scene meshes (gbuffer,
// gbuffer.textured, forward, shadows, skyocc.heightfield): model transform,
// vegetation sway, the previous frame's position (motion vectors), clip
// positions, normal and tangent. One place for instancing and wind; the
// passes bind `objects` and their view and pass in what this needs.
#import scene
#import gbuffer_io

// World position of the vertex at `position` under `model` (o.model, or
// o.prev_model for the previous frame); with `sway` (vegetation pipelines)
// displaced by the wind at time t (s).
fn object_world(o: Object, model: mat4x4f, position: vec3f, uv: vec2f, sway: bool, t: f32) -> vec4f {
    var world = model * vec4f(position, 1.0);
    if (sway) {
        world += vec4f(foliage_sway(o, position, uv, world.xz, t), 0.0);
    }
    return world;
}

struct ObjectVertex {
    world: vec4f,
    prev_world: vec4f,
    // view_proj * world, prev_view_proj * prev_world
    clip: vec4f,
    prev_clip: vec4f,
    // world normal (normal matrix), not normalised
    normal: vec3f,
    // world tangent direction (model); the caller decides its sign (w)
    tangent: vec3f,
}

// Vertex `vertex_in` of object o. view_proj and prev_view_proj carry their
// frame's jitter (the AA contract); time: (now, previous frame) in s, so the
// motion vectors cover the sway.
fn object_vertex(o: Object, vertex_in: GBufferVertexIn, view_proj: mat4x4f, prev_view_proj: mat4x4f,
        sway: bool, time: vec2f) -> ObjectVertex {
    var v: ObjectVertex;
    v.world = object_world(o, o.model, vertex_in.position, vertex_in.uv, sway, time.x);
    v.prev_world = object_world(o, o.prev_model, vertex_in.position, vertex_in.uv, sway, time.y);
    v.clip = view_proj * v.world;
    v.prev_clip = prev_view_proj * v.prev_world;
    v.normal = (o.normal_matrix * vec4f(vertex_in.normal, 0.0)).xyz;
    v.tangent = (o.model * vec4f(vertex_in.tangent.xyz, 0.0)).xyz;
    return v;
}
