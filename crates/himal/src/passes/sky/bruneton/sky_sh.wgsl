// sky.sh (L1): the Bruneton sky (incl. the below-horizon ground fill and the
// night floor, no sun disk) projected onto 9 SH coefficients in one workgroup:
// Gauss-Legendre rows in t = dir.y per hemisphere times 2 x rows uniform
// azimuths, the quadrature of math/sh.rs `Sh9Rgb::project`. Output: radiance
// coefficients (the CPU convolves them to irradiance). Twin: `Sh9Rgb::project`
// of reference.rs `CpuTables::sky_radiance`.
#import atmosphere
#import sh
#import math

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var transmittance_load: texture_2d<f32>;
@group(0) @binding(2) var scattering: texture_3d<f32>;
@group(0) @binding(3) var single_mie: texture_3d<f32>;
@group(0) @binding(4) var irradiance: texture_2d<f32>;
@group(0) @binding(5) var table_sampler: sampler;
// xyz: unit vector towards the sun
@group(0) @binding(6) var<uniform> sun: vec4f;
// Per row: t = cos(theta) and its weight (Gauss-Legendre weight x dt x dphi).
@group(0) @binding(7) var<storage, read> rows: array<vec2f>;
@group(0) @binding(8) var<storage, read_write> out_sh: array<vec4f, 9>;

const SH_THREADS: u32 = 64u;
var<workgroup> partial: array<array<vec3f, 9>, SH_THREADS>;

@compute @workgroup_size(64, 1, 1)
fn cs_sky_sh(@builtin(local_invocation_index) tid: u32) {
    let row_count = arrayLength(&rows);
    let n_phi = 2u * row_count;
    let dphi = TAU / f32(n_phi);
    var acc: array<vec3f, 9>;
    for (var k = 0u; k < 9u; k++) {
        acc[k] = vec3f(0.0);
    }
    for (var i = tid; i < row_count * n_phi; i += SH_THREADS) {
        let row = rows[i / n_phi];
        let phi = (f32(i % n_phi) + 0.5) * dphi;
        let s = sqrt(max(1.0 - row.x * row.x, 0.0));
        let d = vec3f(s * cos(phi), row.x, s * sin(phi));
        let l = bruneton_sky_radiance(
            atmosphere, transmittance_load, scattering, single_mie, irradiance, table_sampler, d, sun.xyz) * row.y;
        let y = sh9_basis(d);
        for (var k = 0u; k < 9u; k++) {
            acc[k] += l * y[k];
        }
    }
    partial[tid] = acc;
    workgroupBarrier();
    if (tid < 9u) {
        var sum = vec3f(0.0);
        for (var t = 0u; t < SH_THREADS; t++) {
            sum += partial[t][tid];
        }
        out_sh[tid] = vec4f(sum, 0.0);
    }
}
