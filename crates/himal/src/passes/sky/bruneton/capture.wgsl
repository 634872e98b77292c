// sky.capture (L1 -> L4 input): the Bruneton sky (no sun disk: the sun is lit
// analytically) into mip 0 of the environment source cube, faces in z; the
// Bruneton twin of passes/envmap/capture.wgsl.
#import atmosphere
#import envmap
#import sky

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var transmittance_load: texture_2d<f32>;
@group(0) @binding(2) var scattering: texture_3d<f32>;
@group(0) @binding(3) var single_mie: texture_3d<f32>;
@group(0) @binding(4) var irradiance: texture_2d<f32>;
@group(0) @binding(5) var table_sampler: sampler;
@group(0) @binding(6) var<uniform> sky: SkyParams;
@group(0) @binding(7) var out_texture: texture_storage_2d_array<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_capture_bruneton(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_texture);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let uv = (vec2f(id.xy) + 0.5) / vec2f(size);
    let radiance = bruneton_sky_radiance(atmosphere, transmittance_load, scattering, single_mie, irradiance,
        table_sampler, cube_face_direction(id.z, uv), sky.sun_direction.xyz);
    textureStore(out_texture, id.xy, id.z, vec4f(radiance, 1.0));
}
