// Environment maps (TECHNIQUES L4, M4): cube-face directions, GGX sampling
// for the filtered importance sampling and the DFG table, and the M4
// distorted reflection normal. Twin: passes/envmap/reference.rs.
#import math

// Unit direction through texel coordinate uv in [0,1]^2 (v down) of cube face
// `face` (+X, -X, +Y, -Y, +Z, -Z), the Vulkan / D3D cube convention.
fn cube_face_direction(face: u32, uv: vec2f) -> vec3f {
    let s = uv.x * 2.0 - 1.0;
    let t = uv.y * 2.0 - 1.0;
    var d: vec3f;
    switch face {
        case 0u: { d = vec3f(1.0, -t, -s); }
        case 1u: { d = vec3f(-1.0, -t, s); }
        case 2u: { d = vec3f(s, 1.0, t); }
        case 3u: { d = vec3f(s, -1.0, -t); }
        case 4u: { d = vec3f(s, -t, 1.0); }
        default: { d = vec3f(-s, -t, -1.0); }
    }
    return normalize(d);
}

// Point i of the n-point Hammersley set (24-bit radical inverse, as math/sampling.rs).
fn envmap_hammersley(i: u32, n: u32) -> vec2f {
    return vec2f(f32(i) / f32(max(n, 1u)), f32(reverseBits(i) >> 8u) * (1.0 / 16777216.0));
}

// Isotropic GGX half vector around +z, distributed as D(h) (h.z).
fn envmap_sample_ggx(u: vec2f, alpha: f32) -> vec3f {
    let phi = TAU * u.y;
    let r = sqrt(saturate(u.x));
    let h = vec3f(alpha * r * cos(phi), alpha * r * sin(phi), sqrt(saturate(1.0 - u.x)));
    return normalize(h);
}

// An orthonormal basis (x, y) around unit n (Duff et al. 2017).
fn envmap_basis(n: vec3f) -> mat3x3f {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let x = vec3f(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let y = vec3f(b, sign + n.y * n.y * a, -n.y);
    return mat3x3f(x, y, n);
}

// M4 (Far Cry 4): the reflection normal bent toward the grain,
//   anisoTangent = cross(view, binormal); anisoNormal = cross(anisoTangent, binormal);
//   reflNormal = normalize(lerp(normal, anisoNormal, anisotropy)).
// The talk's `view` is the incident direction (camera to point) = -v, so
// anisoNormal is v's part perpendicular to the binormal (docs/techniques/M4.md).
fn m4_reflection_normal(n: vec3f, b: vec3f, v: vec3f, anisotropy: f32) -> vec3f {
    let aniso_tangent = cross(-v, b);
    let aniso_normal = cross(aniso_tangent, b);
    let bent = mix(n, aniso_normal, anisotropy);
    let len = length(bent);
    return select(n, bent / len, len > 1e-6);
}
