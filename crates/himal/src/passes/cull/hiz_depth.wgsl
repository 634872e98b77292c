// cull.hiz (V6 Hi-Z, issue #17 item 5): mip 0 of the min-depth pyramid, the
// frame's depth (after the G-buffer and the terrain) copied into R32Float so
// later mips can be written as storage. Twin: reference.rs `hiz_build`.

@group(0) @binding(0) var depth: texture_depth_2d;
@group(0) @binding(1) var child: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_depth(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(child);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    textureStore(child, id.xy, vec4f(textureLoad(depth, id.xy, 0), 0.0, 0.0, 1.0));
}
