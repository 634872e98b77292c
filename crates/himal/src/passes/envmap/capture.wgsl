// envmap.capture (TECHNIQUES L4 input): sky radiance (Preetham, no sun disk:
// the sun is lit analytically) into mip 0 of the source cube, faces in z.
#import sky
#import envmap

@group(0) @binding(0) var<uniform> sky: SkyParams;
@group(0) @binding(1) var out_texture: texture_storage_2d_array<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_capture(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_texture);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let uv = (vec2f(id.xy) + 0.5) / vec2f(size);
    let radiance = preetham_sky_radiance(sky, cube_face_direction(id.z, uv));
    textureStore(out_texture, id.xy, id.z, vec4f(radiance, 1.0));
}
