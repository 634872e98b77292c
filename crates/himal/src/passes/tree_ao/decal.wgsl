// vegetation.ao (V4, docs/techniques/V4.md "In the frame"): each tree's
// occlusion volume as a deferred decal. One instanced draw of every tree's
// volume box (36 vertices each; back faces only, so each covered pixel is
// shaded once, the camera inside a box too); the fragment reconstructs the
// pixel's world position from depth, takes it into the tree's space
// through the inverse model (the transpose of `normal_matrix`), and writes
// the faded volume sample A, which the target multiplies in (blend
// dst * src): the G-buffer albedo's alpha (the occlusion lighting applies
// to the sky and ambient light), or the `--view tree-ao` factor target.
// Overlapping boxes compose by the product. CPU twin: scene/tree/ao.rs
// `AoVolume::factor` (passes/tree_ao/reference.rs).
#import view
#import scene

// Twin of gpu_scene/tree_ao.rs `AoVolumeGpu`.
struct AoVolume {
    // xyz: box minimum (tree space, m); w: the slab's first texel along z
    min: vec4f,
    // xyz: box extent (m)
    extent: vec4f,
    // xyz: voxels per axis
    res: vec4u,
}

// Width of the fade to 1 at the side and top faces (a fraction of the box
// per axis; scene/tree/ao.rs EDGE_FADE).
const EDGE_FADE: f32 = 0.15;

// The box's triangles, counter-clockwise seen from outside; corner i is
// (i & 1, (i >> 1) & 1, (i >> 2) & 1).
const BOX = array<u32, 36>(0u, 6u, 2u, 0u, 4u, 6u, 1u, 7u, 5u, 1u, 3u, 7u, 0u, 5u, 4u, 0u, 1u, 5u,
    2u, 7u, 3u, 2u, 6u, 7u, 0u, 3u, 1u, 0u, 2u, 3u, 4u, 7u, 6u, 4u, 5u, 7u);

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// (leaves object's GPU index, volume) per tree.
@group(0) @binding(2) var<storage, read> trees: array<vec2u>;
@group(0) @binding(3) var<storage, read> volumes: array<AoVolume>;
// R8Unorm, the volumes' slabs stacked along z.
@group(0) @binding(4) var atlas: texture_3d<f32>;
@group(0) @binding(5) var atlas_sampler: sampler;
@group(0) @binding(6) var depth: texture_depth_2d;

struct VsOut {
    @builtin(position) position: vec4f,
    @location(0) @interpolate(flat) tree: u32,
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32, @builtin(instance_index) tree: u32) -> VsOut {
    let t = trees[tree];
    let v = volumes[t.y];
    let model = objects[t.x].model;
    let i = BOX[vertex];
    var c = vec3f(f32(i & 1u), f32((i >> 1u) & 1u), f32((i >> 2u) & 1u));
    // A mirroring transform turns the winding: mirror the box in x too.
    if (determinant(mat3x3f(model[0].xyz, model[1].xyz, model[2].xyz)) < 0.0) {
        c.x = 1.0 - c.x;
    }
    let local = v.min.xyz + c * v.extent.xyz;
    var out: VsOut;
    out.position = view.view_proj * (model * vec4f(local, 1.0));
    out.tree = tree;
    return out;
}

// The volume's trilinear sample at tree-space `p`, clamped to the voxel
// centres (AoVolume::sample), faded to 1 toward the side and top faces;
// 1 outside the box.
fn tree_ao_factor(v: AoVolume, p: vec3f) -> f32 {
    let u = (p - v.min.xyz) / max(v.extent.xyz, vec3f(1e-6));
    if (any(u < vec3f(0.0)) || any(u > vec3f(1.0))) {
        return 1.0;
    }
    let res = vec3f(v.res.xyz);
    let g = clamp(u * res, vec3f(0.5), res - 0.5);
    let size = vec3f(textureDimensions(atlas));
    let a = textureSampleLevel(atlas, atlas_sampler, (g + vec3f(0.0, 0.0, v.min.w)) / size, 0.0).x;
    let edge = min(min(min(u.x, 1.0 - u.x), min(u.z, 1.0 - u.z)), 1.0 - u.y);
    let fade = smoothstep(0.0, 1.0, edge / EDGE_FADE);
    return 1.0 + (a - 1.0) * fade;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4f {
    let d = textureLoad(depth, vec2i(in.position.xy), 0);
    if (d <= 0.0) {
        discard;
    }
    let t = trees[in.tree];
    let p = world_at_fragment(view, in.position.xy, d);
    let local = (transpose(objects[t.x].normal_matrix) * vec4f(p, 1.0)).xyz;
    let a = tree_ao_factor(volumes[t.y], local);
    if (a >= 1.0) {
        discard;
    }
    return vec4f(a);
}
