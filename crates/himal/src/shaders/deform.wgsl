// The previous frame's positions of the deformed vertices (SceneGpu::deform):
// `passes/skin` writes them from the previous time's morph weights and
// joints, so motion vectors carry the deformation (docs/gltf.md, "Animation and
// skinning").
// Element 0: (first vertex, count) as u32 bits; 1 + i: vertex first + i
// (model space; the object's prev_model places it). `--deform-motion off`
// binds a header of count 0.
@group(0) @binding(3) var<storage, read> deform_prev: array<vec4f>;

// The previous frame's model-space position of vertex `vertex` (the draw's
// vertex index, base vertex included): its deformed one inside the deformed
// range, else `position` (rigid: only the object's transform moved).
fn deform_prev_position(vertex: u32, position: vec3f) -> vec3f {
    let first = bitcast<u32>(deform_prev[0].x);
    let count = bitcast<u32>(deform_prev[0].y);
    if (vertex >= first && vertex - first < count) {
        return deform_prev[1u + vertex - first].xyz;
    }
    return position;
}
