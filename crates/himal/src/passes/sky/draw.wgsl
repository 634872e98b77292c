// sky: sky radiance and the sun disk where no geometry was drawn (depth test
// Equal against the cleared reverse-Z value 0). TECHNIQUES L1. SKY_MODEL 0:
// Preetham (twin passes/sky/preetham.rs); 1: Bruneton tables (twin
// passes/sky/bruneton/reference.rs); the sun disk is Preetham's in both.
#import view
#import sky
#import atmosphere
#import math

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> sky: SkyParams;
// An HDR environment (equirectangular) drawn instead of the sky (issue #8);
// twin: scene/environment.rs `EnvironmentImage::uv`.
@group(0) @binding(2) var environment: texture_2d<f32>;
@group(0) @binding(3) var environment_sampler: sampler;

// Bruneton tables (the graph's fallbacks while SKY_MODEL = 0).
@group(0) @binding(4) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(5) var transmittance_load: texture_2d<f32>;
@group(0) @binding(6) var scattering: texture_3d<f32>;
@group(0) @binding(7) var single_mie: texture_3d<f32>;
@group(0) @binding(8) var irradiance: texture_2d<f32>;
@group(0) @binding(9) var table_sampler: sampler;

override ENVIRONMENT: bool = false;
// 0: Preetham, 1: Bruneton (SkyModel).
override SKY_MODEL: u32 = 0u;
override ENV_ROTATION: f32 = 0.0;

struct VertexOut {
    // invariant: the depth test Equal 0 must see exactly the written value
    @builtin(position) @invariant clip: vec4f,
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> VertexOut {
    var out: VertexOut;
    out.clip = fullscreen_clip(i);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4f {
    let dir = view_ray(view, in.clip.xy * view.viewport.zw);
    if (ENVIRONMENT) {
        let phi = atan2(dir.x, -dir.z) + ENV_ROTATION;
        let u = fract(phi / TAU + 0.5);
        let v = acos(clamp(dir.y, -1.0, 1.0)) / PI;
        return vec4f(textureSampleLevel(environment, environment_sampler, vec2f(u, v), 0.0).rgb, 1.0);
    }
    var c = sun_disk_radiance(sky, dir);
    if (SKY_MODEL == 1u) {
        c += bruneton_sky_radiance(atmosphere, transmittance_load, scattering, single_mie, irradiance,
            table_sampler, dir, sky.sun_direction.xyz);
    } else {
        c += preetham_sky_radiance(sky, dir);
    }
    return vec4f(c, 1.0);
}
