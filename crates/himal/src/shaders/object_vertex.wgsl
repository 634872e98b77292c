// The object vertex stage of every pass that draws scene meshes (gbuffer,
// gbuffer.textured, forward, shadows, skyocc.heightfield): model transform,
// vegetation sway, the previous frame's position (motion vectors), clip
// positions, normal and tangent. One place for instancing and wind; the
// passes bind `objects` (read here for V2's tree bones) and their view and
// pass in what this needs.
#import scene
#import gbuffer_io

// V2: the first bone record of a tree object (params.y = -(1 + first);
// gpu_scene/trees.rs), or -1 for any other object.
fn object_tree_first(o: Object) -> i32 {
    if (o.params.y < 0.0) {
        return i32(round(-o.params.y)) - 1;
    }
    return -1;
}

// V5 branch motion (Sousa 2007, GPU Gems 3 ch. 16): smooth triangle waves,
// in [0, 1], for speed where sines were.
fn smooth_triangle(x: vec4f) -> vec4f {
    let t = abs(fract(x + 0.5) * 2.0 - 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// Metres of V5 wave per m/s of wind at full weight: macro (X, Y, Z: the
// branch) and micro (X, Z: its leaves, phased per vertex).
const BRANCH_MACRO: f32 = 0.012;
const BRANCH_MICRO: f32 = 0.004;

// V5: the branch waves of a vertex at `local` with `phase`, at time t in a
// wind of `speed` (m/s), scaled by weight (CPU twin reference.rs `waves`).
fn branch_waves(phase: f32, local: vec3f, t: f32, speed: f32, weight: f32) -> vec3f {
    let m = smooth_triangle(vec4f(0.31 * t + phase, 0.23 * t + 1.3 * phase, 0.27 * t + 0.7 * phase, 0.0)) * 2.0 - 1.0;
    let vp = dot(local, vec3f(0.71, 0.53, 0.37));
    let u = smooth_triangle(vec4f(1.9 * t + vp + phase, 2.3 * t + 1.7 * vp + phase, 0.0, 0.0)) * 2.0 - 1.0;
    return (weight * speed) * (BRANCH_MACRO * m.xyz + BRANCH_MICRO * vec3f(u.x, 0.0, u.y));
}

// V2: a tree vertex bent by its bones (passes/vegetation writes their
// world transforms into `objects`, which the importer declares; CPU twin
// passes/vegetation/reference.rs `deform`): the trunk bends all of it by
// (y / height)^2 about the root, branch bone b (uv1 = (b, weight)) adds
// weight * (its transform - the trunk's), and V5's waves weight * speed.
// An impostor grid point (impostor true) waves by (y / height)^2 at the
// trunk's wind. prev: the previous frame's (bones, speed; t is its time).
fn tree_world(o: Object, first: u32, position: vec3f, uv1: vec2f, prev: bool, t: f32, impostor: bool) -> vec4f {
    let p = vec4f(position, 1.0);
    let trunk = objects[first];
    var model = o.model;
    var w0 = trunk.model;
    var speed = trunk.params.y;
    if (prev) {
        model = o.prev_model;
        w0 = trunk.prev_model;
        speed = trunk.params.z;
    }
    let rest = model * p;
    let h = clamp(position.y * trunk.params.x, 0.0, 1.0);
    let bent = w0 * p;
    var world = rest + (bent - rest) * (h * h);
    let phase = 0.13 * model[3].x + 0.17 * model[3].z;
    let b = u32(max(uv1.x, 0.0) + 0.5);
    if (impostor) {
        world += vec4f(branch_waves(phase, position, t, speed, h * h), 0.0);
    } else if (uv1.x >= 0.0 && b > 0u && b < 4u) {
        let bone = objects[first + b];
        var wb = bone.model;
        var s = bone.params.y;
        if (prev) {
            wb = bone.prev_model;
            s = bone.params.z;
        }
        world += (wb * p - bent) * uv1.y;
        world += vec4f(branch_waves(phase + 1.7 * f32(b), position, t, s, uv1.y), 0.0);
    }
    return vec4f(world.xyz, 1.0);
}

// World position of the vertex at `position` (uv, uv1 its texture
// coordinates) at this frame (prev false: o.model) or the previous one
// (o.prev_model); trees bend by their bones, and with `sway` (vegetation
// pipelines) other foliage is displaced by the wind at time t (s).
fn object_world(o: Object, prev: bool, position: vec3f, uv: vec2f, uv1: vec2f, sway: bool, t: f32) -> vec4f {
    let first = object_tree_first(o);
    if (first >= 0) {
        return tree_world(o, u32(first), position, uv1, prev, t, false);
    }
    var model = o.model;
    if (prev) {
        model = o.prev_model;
    }
    var world = model * vec4f(position, 1.0);
    if (sway) {
        world += vec4f(foliage_sway(o, position, uv, world.xz, t), 0.0);
    }
    return world;
}

// V3 impostor grid point `local` (tree space) in the world at time t:
// trees bend it with their trunk (their branches are inside the captures)
// and V5's waves bring it to life.
fn impostor_world(o: Object, local: vec3f, prev: bool, t: f32) -> vec4f {
    let first = object_tree_first(o);
    if (first >= 0) {
        return tree_world(o, u32(first), local, vec2f(0.0), prev, t, true);
    }
    if (prev) {
        return o.prev_model * vec4f(local, 1.0);
    }
    return o.model * vec4f(local, 1.0);
}

// World position at rest (no wind): passes that must not see motion
// (sky-occlusion height fields) and glTF casters.
fn object_rest(o: Object, position: vec3f) -> vec4f {
    return o.model * vec4f(position, 1.0);
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
    v.world = object_world(o, false, vertex_in.position, vertex_in.uv, vertex_in.uv1, sway, time.x);
    v.prev_world = object_world(o, true, vertex_in.position, vertex_in.uv, vertex_in.uv1, sway, time.y);
    v.clip = view_proj * v.world;
    v.prev_clip = prev_view_proj * v.prev_world;
    v.normal = (o.normal_matrix * vec4f(vertex_in.normal, 0.0)).xyz;
    v.tangent = (o.model * vec4f(vertex_in.tangent.xyz, 0.0)).xyz;
    return v;
}
