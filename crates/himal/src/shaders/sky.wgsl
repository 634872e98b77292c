// L1 sky foundation: Preetham, Shirley & Smits 1999 analytic sky and the sun
// disk. Twin of crates/himal/src/passes/sky/preetham.rs (PreethamSky::radiance,
// PreethamSky::sun_disk_radiance). Radiance in kcd/m^2 (Preetham's Y unit) as
// linear Rec.709; sun illuminance in klux. No PI needed here.

// Twin of SkyGpuParams (12 x vec4f = 192 bytes).
struct SkyParams {
    // Perez coefficients A..E, each (x, y, Y, 0).
    perez_a: vec4f,
    perez_b: vec4f,
    perez_c: vec4f,
    perez_d: vec4f,
    perez_e: vec4f,
    // Zenith (x, y, Y kcd/m^2); w = twilight radiance scale.
    zenith_xyy: vec4f,
    // 1 / F(0, theta_s) for (x, y, Y); w = ground blend width in -dir.y.
    perez_inv_norm: vec4f,
    // Below-horizon fill, CIE XYZ before the twilight scale.
    ground_xyz: vec4f,
    // Sun direction of the sky model (theta_s clamped); w = min cos(theta).
    sun_dir_model: vec4f,
    // True sun direction (towards the sun).
    sun_direction: vec4f,
    // Sun illuminance at the ground, linear RGB klux.
    sun_illuminance: vec4f,
    // Soft disk: inner, outer angle (rad), 1 / solid angle, unused.
    sun_disk: vec4f,
}

// CIE xyY -> XYZ, z clamped at 0 as in Mitsuba's sky.cpp.
fn sky_xyy_to_xyz(xyy: vec3f) -> vec3f {
    if (xyy.y <= 1e-6) {
        return vec3f(0.0);
    }
    let y_over = xyy.z / xyy.y;
    return vec3f(xyy.x * y_over, xyy.z, max(1.0 - xyy.x - xyy.y, 0.0) * y_over);
}

// CIE XYZ -> linear Rec.709 / sRGB (D65), IEC 61966-2-1.
fn sky_xyz_to_linear_srgb(xyz: vec3f) -> vec3f {
    return vec3f(
        3.2404542 * xyz.x - 1.5371385 * xyz.y - 0.4985314 * xyz.z,
        -0.9692660 * xyz.x + 1.8760108 * xyz.y + 0.0415560 * xyz.z,
        0.0556434 * xyz.x - 0.2040259 * xyz.y + 1.0572252 * xyz.z,
    );
}

fn xyy_to_linear_srgb(xyy: vec3f) -> vec3f {
    return sky_xyz_to_linear_srgb(sky_xyy_to_xyz(xyy));
}

// Perez: F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma),
// for (x, y, Y) at once.
fn preetham_perez_f(p: SkyParams, cos_theta: f32, gamma: f32, cos_gamma: f32) -> vec3f {
    let b_term = exp(p.perez_b.xyz / cos_theta);
    let d_term = exp(p.perez_d.xyz * gamma);
    return (1.0 + p.perez_a.xyz * b_term)
        * (1.0 + p.perez_c.xyz * d_term + p.perez_e.xyz * (cos_gamma * cos_gamma));
}

// Model XYZ above the horizon (unit dir), before the twilight scale.
fn preetham_model_xyz(p: SkyParams, dir: vec3f) -> vec3f {
    let cos_theta = max(dir.y, p.sun_dir_model.w);
    let cos_gamma = clamp(dot(dir, p.sun_dir_model.xyz), -1.0, 1.0);
    let f = preetham_perez_f(p, cos_theta, acos(cos_gamma), cos_gamma);
    return sky_xyy_to_xyz(p.zenith_xyy.xyz * f * p.perez_inv_norm.xyz);
}

// Sky radiance (linear RGB, kcd/m^2) towards unit direction dir. Below the
// horizon: the horizon value at the same azimuth blended into the ground fill.
fn preetham_sky_radiance(p: SkyParams, dir: vec3f) -> vec3f {
    var xyz: vec3f;
    if (dir.y >= 0.0) {
        xyz = preetham_model_xyz(p, dir);
    } else {
        let blend = smoothstep(0.0, p.perez_inv_norm.w, -dir.y);
        let h = vec3f(dir.x, 0.0, dir.z);
        let h_len = length(h);
        var horizon = vec3f(0.0);
        if (h_len > 0.0) {
            horizon = preetham_model_xyz(p, h / h_len);
        }
        xyz = mix(horizon, p.ground_xyz.xyz, blend);
    }
    return max(sky_xyz_to_linear_srgb(xyz * p.zenith_xyy.w), vec3f(0.0));
}

// Soft sun disk (linear RGB, kcd/m^2): illuminance / solid angle inside the
// disk, 1 - smoothstep(inner, outer, angle) across the edge so it stays visible
// at low resolution; integrates to the sun illuminance.
fn sun_disk_radiance(p: SkyParams, dir: vec3f) -> vec3f {
    let sun = p.sun_direction.xyz;
    if (dot(dir, sun) <= 0.0) {
        return vec3f(0.0);
    }
    // asin(|d x s|) keeps precision at the tiny angles where acos(dot) does not.
    let angle = asin(min(length(cross(dir, sun)), 1.0));
    let profile = 1.0 - smoothstep(p.sun_disk.x, p.sun_disk.y, angle);
    return p.sun_illuminance.xyz * (profile * p.sun_disk.z);
}
