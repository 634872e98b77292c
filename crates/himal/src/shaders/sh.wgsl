// Third-order (9-coefficient) real spherical harmonics (L1 sky light).
// Twin of crates/himal/src/math/sh.rs: same basis on the direction's own
// components, coefficient order L00, L1-1, L10, L11, L2-2, L2-1, L20, L21, L22.
// Source: Ramamoorthi & Hanrahan 2001; Sloan, "Stupid SH tricks" 2008.
#import math

// rgb in xyz, w unused (Sh9Gpu on the CPU side).
struct Sh9 {
    c: array<vec4f, 9>,
}

fn sh9_basis(d: vec3f) -> array<f32, 9> {
    return array<f32, 9>(
        0.282095,
        0.488603 * d.y,
        0.488603 * d.z,
        0.488603 * d.x,
        1.092548 * d.x * d.y,
        1.092548 * d.y * d.z,
        0.315392 * (3.0 * d.z * d.z - 1.0),
        1.092548 * d.x * d.z,
        0.546274 * (d.x * d.x - d.y * d.y),
    );
}

// Evaluates the stored coefficients as-is. The renderer uploads irradiance
// coefficients (Sh9Rgb::radiance_to_irradiance_coeffs), so this gives E(n).
fn sh9_eval(sh: Sh9, d: vec3f) -> vec3f {
    let y = sh9_basis(d);
    // Unrolled: dynamic indexing of value arrays is poorly supported by backends.
    return sh.c[0].xyz * y[0] + sh.c[1].xyz * y[1] + sh.c[2].xyz * y[2]
        + sh.c[3].xyz * y[3] + sh.c[4].xyz * y[4] + sh.c[5].xyz * y[5]
        + sh.c[6].xyz * y[6] + sh.c[7].xyz * y[7] + sh.c[8].xyz * y[8];
}

// Radiance along d from irradiance coefficients: each band divided by the
// cosine lobe's A_l (pi, 2pi/3, pi/4), i.e. the band-limited radiance the
// irradiance was convolved from. Twin: Sh9Rgb::radiance_from_irradiance_eval.
fn sh9_eval_radiance_from_irradiance(sh: Sh9, d: vec3f) -> vec3f {
    let y = sh9_basis(d);
    let l0 = sh.c[0].xyz * y[0];
    let l1 = sh.c[1].xyz * y[1] + sh.c[2].xyz * y[2] + sh.c[3].xyz * y[3];
    let l2 = sh.c[4].xyz * y[4] + sh.c[5].xyz * y[5] + sh.c[6].xyz * y[6]
        + sh.c[7].xyz * y[7] + sh.c[8].xyz * y[8];
    return l0 / PI + l1 * (3.0 / (2.0 * PI)) + l2 * (4.0 / PI);
}
