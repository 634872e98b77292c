// M3: tangent frame as a quaternion in 10:10:10:2 (McAuley GDC 2015 appendix
// A; Frey 2011; Frykholm 2009). GPU twin of src/math/quat_frame.rs; see
// docs/techniques/M3.md. Quaternions are vec4f(x, y, z, w) with
// q * X = t, q * Y = b, q * Z = n (the appendix's quaternion is the
// conjugate). The G-buffer holds right-handed frames only: a mirrored
// frame's sign (tangent.w) is used by apply_normal_map before packing.

// Shepperd's method: the appendix's w = 1 + trace is 0/0 at half turns.
fn frame_to_quat(t: vec3f, b: vec3f, n: vec3f) -> vec4f {
    let trace = t.x + b.y + n.z;
    var q: vec4f;
    if trace > 0.0 {
        let s = 2.0 * sqrt(1.0 + trace);
        q = vec4f((b.z - n.y) / s, (n.x - t.z) / s, (t.y - b.x) / s, 0.25 * s);
    } else if t.x > b.y && t.x > n.z {
        let s = 2.0 * sqrt(1.0 + t.x - b.y - n.z);
        q = vec4f(0.25 * s, (b.x + t.y) / s, (n.x + t.z) / s, (b.z - n.y) / s);
    } else if b.y > n.z {
        let s = 2.0 * sqrt(1.0 + b.y - t.x - n.z);
        q = vec4f((b.x + t.y) / s, 0.25 * s, (n.y + b.z) / s, (n.x - t.z) / s);
    } else {
        let s = 2.0 * sqrt(1.0 + n.z - t.x - b.y);
        q = vec4f((n.x + t.z) / s, (n.y + b.z) / s, 0.25 * s, (t.y - b.x) / s);
    }
    return normalize(q);
}

// The appendix's QuaternionToTangentSpace in our convention; columns t, b, n.
fn quat_to_frame(q: vec4f) -> mat3x3f {
    let x = q.x;
    let y = q.y;
    let z = q.z;
    let w = q.w;
    return mat3x3f(
        vec3f(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + z * w), 2.0 * (x * z - y * w)),
        vec3f(2.0 * (x * y - z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + x * w)),
        vec3f(2.0 * (x * z + y * w), 2.0 * (y * z - x * w), 1.0 - 2.0 * (x * x + y * y)),
    );
}

// Index of the largest |component|, ties to the lower index (no
// CubeMapFaceID in WGSL; same rule as the CPU twin).
fn quat_largest_component(q: vec4f) -> u32 {
    let a = abs(q);
    var index = 0u;
    var m = a.x;
    if a.y > m { index = 1u; m = a.y; }
    if a.z > m { index = 2u; m = a.z; }
    if a.w > m { index = 3u; }
    return index;
}

// Appendix PackQuaternion: smallest three in [-1/sqrt2, 1/sqrt2] -> [0,1],
// sign flipped so the dropped component is positive, index / 3 in w.
// Write the result to an Rgb10a2Unorm target.
fn pack_quat(q: vec4f) -> vec4f {
    let index = quat_largest_component(q);
    var r = q;
    if index == 0u { r = q.yzwx; }
    if index == 1u { r = q.xzwy; }
    if index == 2u { r = q.xywz; }
    let s = select(1.0, -1.0, r.w < 0.0);
    return vec4f(r.xyz * (s * 0.70710678) + 0.5, f32(index) / 3.0);
}

// Appendix UnpackQuaternion; the index is rounded, not truncated.
fn unpack_quat(p: vec4f) -> vec4f {
    let index = u32(round(p.w * 3.0));
    let xyz = p.xyz * 1.41421356 - 0.70710678;
    var q = vec4f(xyz, sqrt(1.0 - saturate(dot(xyz, xyz))));
    if index == 0u { q = q.wxyz; }
    if index == 1u { q = q.xwyz; }
    if index == 2u { q = q.xywz; }
    return q;
}

// Unit vector perpendicular to unit n (Duff et al. 2017).
fn tangent_frame_any_perpendicular(n: vec3f) -> vec3f {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    return vec3f(1.0 + s * n.x * n.x * a, s * n.x * n.y * a, -s * n.x);
}

// Right-handed shading frame (t, cross(n, t), n) from a vertex tangent
// Gram-Schmidt'ed against n; tangent.w is ignored (see apply_normal_map).
fn shading_frame(n_in: vec3f, tangent: vec4f) -> mat3x3f {
    let n = normalize(n_in);
    let t_raw = tangent.xyz - n * dot(n, tangent.xyz);
    let len2 = dot(t_raw, t_raw);
    let t = select(tangent_frame_any_perpendicular(n), t_raw * inverseSqrt(len2), len2 > 1e-24);
    return mat3x3f(t, cross(n, t), n);
}

// Tangent-space normal -> world, glTF bitangent cross(n, t) * tangent.w:
// where a mirrored frame's sign is consumed, before shading_frame and packing.
fn apply_normal_map(n: vec3f, tangent: vec4f, ts_normal: vec3f) -> vec3f {
    let f = shading_frame(n, tangent);
    let w = select(1.0, -1.0, tangent.w < 0.0);
    return normalize(f[0] * ts_normal.x + f[1] * (w * ts_normal.y) + f[2] * ts_normal.z);
}
