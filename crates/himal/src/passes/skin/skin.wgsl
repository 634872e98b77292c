// Skinning (glTF 2.0 3.7.3): each skinned vertex blended by its joints,
// and its position again by the previous frame's joints into `prev` (the
// G-buffer's motion vectors, shaders/deform.wgsl),
// M = sum_i w_i J[j_i]; p' = M p, n' = normalize(M n), t' = M t made
// orthogonal to n' and normalised (a direction M collapses keeps its
// bind-pose value). Written into the
// scene-layout vertex (VERTEX_FLOATS floats: position 0..3, normal 3..6,
// tangent 6..10; the rest is left as uploaded). CPU twin:
// scene::gltf::skin_vertex. docs/gltf.md, "Animation and skinning".

struct SkinVertex {
    position: vec4f,
    normal: vec4f,
    tangent: vec4f,
    weights: vec4f,
    joints: vec4u,
}

struct SkinParams {
    count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: SkinParams;
@group(0) @binding(1) var<storage, read> sources: array<SkinVertex>;
@group(0) @binding(2) var<storage, read> joints: array<mat4x4f>;
@group(0) @binding(3) var<storage, read_write> skinned: array<f32>;
@group(0) @binding(4) var<storage, read> prev_joints: array<mat4x4f>;
// SceneGpu::deform: element 0 is the header deform.wgsl reads (written at
// upload); the skinned vertices are the first of the deformed range.
@group(0) @binding(5) var<storage, read_write> prev: array<vec4f>;

fn normalize_or(v: vec3f, fallback: vec3f) -> vec3f {
    let l = length(v);
    return select(fallback, v / l, l > 0.0 && l < 3.0e38);
}

// size_of::<scene::Vertex>() / 4, set by passes/skin/mod.rs.
override VERTEX_FLOATS: u32;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if (i >= params.count) {
        return;
    }
    let v = sources[i];
    var m = mat4x4f(vec4f(0.0), vec4f(0.0), vec4f(0.0), vec4f(0.0));
    var mp = m;
    for (var k = 0u; k < 4u; k++) {
        if (v.weights[k] != 0.0) {
            m += joints[v.joints[k]] * v.weights[k];
            mp += prev_joints[v.joints[k]] * v.weights[k];
        }
    }
    let p = (m * vec4f(v.position.xyz, 1.0)).xyz;
    prev[1u + i] = vec4f((mp * vec4f(v.position.xyz, 1.0)).xyz, 1.0);
    let n = normalize_or((m * vec4f(v.normal.xyz, 0.0)).xyz, v.normal.xyz);
    // Blended matrices are not rotations: orthogonal to n again.
    let mt = (m * vec4f(v.tangent.xyz, 0.0)).xyz;
    let t = normalize_or(mt - n * dot(n, mt), v.tangent.xyz);
    let o = i * VERTEX_FLOATS;
    skinned[o + 0u] = p.x;
    skinned[o + 1u] = p.y;
    skinned[o + 2u] = p.z;
    skinned[o + 3u] = n.x;
    skinned[o + 4u] = n.y;
    skinned[o + 5u] = n.z;
    skinned[o + 6u] = t.x;
    skinned[o + 7u] = t.y;
    skinned[o + 8u] = t.z;
    skinned[o + 9u] = v.tangent.w;
}
