// envmap.relight (TECHNIQUES L3): a relit probe face, rendered by a camera,
// into its layer of the source cube. Cube faces are seen from inside, so
// their s axis runs opposite to the face camera's right: mirror x.
@group(0) @binding(0) var face_hdr: texture_2d<f32>;
@group(0) @binding(1) var out_texture: texture_storage_2d_array<rgba16float, write>;

override FACE: u32 = 0u;

@compute @workgroup_size(8, 8, 1)
fn cs_mirror(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(face_hdr);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let c = textureLoad(face_hdr, vec2i(i32(size.x - 1u - id.x), i32(id.y)), 0);
    textureStore(out_texture, id.xy, FACE, vec4f(c.rgb, 1.0));
}
