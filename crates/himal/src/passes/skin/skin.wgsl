// Deformation of the scene's animated meshes, one thread per vertex: morph
// targets first, then skinning (glTF 2.0 3.7.2.2 then 3.7.3), and the
// position again at the previous frame's weights and joints into `prev`
// (the G-buffer's motion vectors, shaders/deform.wgsl).
// Morph: P = P0 + sum_k w_k dP_k, N = normalize(N0 + sum_k w_k dN_k),
// T = T0 + sum_k w_k dT_k made orthogonal to N (CPU twin:
// MorphTargets::vertex). Skin: M = sum_i w_i J[j_i] (M = I for a vertex
// with no weight: a mesh that is only morphed); p' = M p,
// n' = normalize(M^-T n) (cofactor matrix), t' = M t made orthogonal to n'
// and normalised (a direction M collapses keeps its input value; CPU twin:
// scene::gltf::skin_vertex). Written into the scene-layout vertex
// (VERTEX_FLOATS floats: position 0..3, normal 3..6, tangent 6..10; the
// rest is left as uploaded). docs/gltf.md, "Animation and skinning".

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
// upload); the deformed vertices are its range from vertex 0.
@group(0) @binding(5) var<storage, read_write> prev: array<vec4f>;
// Per vertex (u32 bits): (first delta after the count entries, targets,
// first weight, 0); then per vertex and target (dP, dN, dT).
@group(0) @binding(6) var<storage, read> morph: array<vec4f>;
// Per morphed mesh: the weights at the frame's time, then at the previous.
@group(0) @binding(7) var<storage, read> weights: array<f32>;

fn normalize_or(v: vec3f, fallback: vec3f) -> vec3f {
    let l = length(v);
    return select(fallback, v / l, l > 0.0 && l < 3.0e38);
}

// glam's Vec3::any_orthonormal_vector (Duff et al. 2017): the tangent of a
// normal its morphed tangent is parallel to.
fn any_orthonormal(n: vec3f) -> vec3f {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    return vec3f(n.x * n.y * a, s + n.y * n.y * a, -n.y);
}

// det(M) M^-T of the upper 3x3 up to its sign (CPU twin:
// scene::gltf::normal_matrix): normals need only the direction.
fn normal_matrix(m: mat4x4f) -> mat3x3f {
    let a = m[0].xyz;
    let b = m[1].xyz;
    let c = m[2].xyz;
    let s = select(1.0, -1.0, dot(a, cross(b, c)) < 0.0);
    return mat3x3f(cross(b, c) * s, cross(c, a) * s, cross(a, b) * s);
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
    var pos = v.position.xyz;
    var nrm = v.normal.xyz;
    var tan = v.tangent.xyz;
    var prev_pos = pos;
    let info = bitcast<vec4u>(morph[i]);
    if (info.y > 0u) {
        for (var k = 0u; k < info.y; k++) {
            let d = params.count + info.x + 3u * k;
            let w = weights[info.z + k];
            pos += w * morph[d].xyz;
            nrm += w * morph[d + 1u].xyz;
            tan += w * morph[d + 2u].xyz;
            prev_pos += weights[info.z + info.y + k] * morph[d].xyz;
        }
        nrm = normalize_or(nrm, vec3f(0.0, 1.0, 0.0));
        let to = tan - nrm * dot(nrm, tan);
        let l = length(to);
        tan = select(any_orthonormal(nrm), to / l, l > 0.0 && l < 3.0e38);
    }
    var m = mat4x4f(vec4f(0.0), vec4f(0.0), vec4f(0.0), vec4f(0.0));
    var mp = m;
    for (var k = 0u; k < 4u; k++) {
        if (v.weights[k] != 0.0) {
            m += joints[v.joints[k]] * v.weights[k];
            mp += prev_joints[v.joints[k]] * v.weights[k];
        }
    }
    if (all(v.weights == vec4f(0.0))) {
        m = mat4x4f(vec4f(1.0, 0.0, 0.0, 0.0), vec4f(0.0, 1.0, 0.0, 0.0),
                    vec4f(0.0, 0.0, 1.0, 0.0), vec4f(0.0, 0.0, 0.0, 1.0));
        mp = m;
    }
    let p = (m * vec4f(pos, 1.0)).xyz;
    prev[1u + i] = vec4f((mp * vec4f(prev_pos, 1.0)).xyz, 1.0);
    let n = normalize_or(normal_matrix(m) * nrm, nrm);
    // Blended matrices are not rotations: orthogonal to n again.
    let mt = (m * vec4f(tan, 0.0)).xyz;
    let t = normalize_or(mt - n * dot(n, mt), tan);
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
