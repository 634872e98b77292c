//! M3: the tangent frame as a quaternion in 10:10:10:2 (McAuley GDC 2015,
//! appendix A; Frey 2011; Frykholm 2009). CPU twin of
//! `shaders/tangent_frame.wgsl`; decisions in `docs/techniques/M3.md`.
//!
//! Convention: `q` rotates the canonical basis onto the frame, i.e.
//! `q * X = t`, `q * Y = b`, `q * Z = n` (glam's). The appendix's
//! TangentSpaceToQuaternion returns the conjugate (the world-to-tangent
//! rotation) and its QuaternionToTangentSpace decodes that convention; ours
//! is the same pair with xyz negated, which changes neither the bits spent
//! nor any error bound.
//!
//! Handedness: the G-buffer stores only right-handed frames
//! (t, b = cross(n, t), n). A mirrored frame's sign (vertex tangent w) is
//! used before packing, to build the normal-mapped normal; every lighting
//! term that reads b only sees b^2 or a double cross product with b, so it is
//! invariant under b -> -b.

use glam::{Quat, Vec3, Vec4};
use std::f32::consts::FRAC_1_SQRT_2;

/// Quaternion of the right-handed orthonormal frame with columns (t, b, n).
///
/// The appendix's `w = 1 + trace` is singular at 180-degree rotations
/// (trace = -1, all four numerators vanish); this is Shepperd's method,
/// which divides by the largest of 4w^2, 4x^2, 4y^2, 4z^2 (>= 1).
pub fn frame_to_quat(t: Vec3, b: Vec3, n: Vec3) -> Quat {
    let (m00, m11, m22) = (t.x, b.y, n.z);
    let trace = m00 + m11 + m22;
    let q = if trace > 0.0 {
        let s = 2.0 * (1.0 + trace).sqrt(); // 4w
        Vec4::new((b.z - n.y) / s, (n.x - t.z) / s, (t.y - b.x) / s, 0.25 * s)
    } else if m00 > m11 && m00 > m22 {
        let s = 2.0 * (1.0 + m00 - m11 - m22).sqrt(); // 4x
        Vec4::new(0.25 * s, (b.x + t.y) / s, (n.x + t.z) / s, (b.z - n.y) / s)
    } else if m11 > m22 {
        let s = 2.0 * (1.0 + m11 - m00 - m22).sqrt(); // 4y
        Vec4::new((b.x + t.y) / s, 0.25 * s, (n.y + b.z) / s, (n.x - t.z) / s)
    } else {
        let s = 2.0 * (1.0 + m22 - m00 - m11).sqrt(); // 4z
        Vec4::new((n.x + t.z) / s, (n.y + b.z) / s, 0.25 * s, (t.y - b.x) / s)
    };
    Quat::from_vec4(q.normalize())
}

/// The frame (t, b, n) of a unit quaternion: the appendix's
/// QuaternionToTangentSpace, written for our convention (its w terms negated).
pub fn quat_to_frame(q: Quat) -> (Vec3, Vec3, Vec3) {
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    let t = Vec3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y + z * w),
        2.0 * (x * z - y * w),
    );
    let b = Vec3::new(
        2.0 * (x * y - z * w),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z + x * w),
    );
    let n = Vec3::new(
        2.0 * (x * z + y * w),
        2.0 * (y * z - x * w),
        1.0 - 2.0 * (x * x + y * y),
    );
    (t, b, n)
}

/// Index of the component with the largest magnitude (x=0, y=1, z=2, w=3);
/// ties go to the lower index, as in the WGSL twin.
pub fn largest_component(q: Vec4) -> usize {
    let a = q.abs();
    let mut index = 0;
    let mut max = a.x;
    for (i, c) in [(1, a.y), (2, a.z), (3, a.w)] {
        if c > max {
            index = i;
            max = c;
        }
    }
    index
}

/// Appendix PackQuaternion: drop the largest component, flip the sign so it
/// is positive (q and -q are the same rotation), rescale the smallest three
/// from [-1/sqrt2, 1/sqrt2] to \[0,1\]; w = index / 3.
pub fn pack_quat(q: Quat) -> Vec4 {
    let q = Vec4::from(q);
    let index = largest_component(q);
    let (three, dropped) = match index {
        0 => (Vec3::new(q.y, q.z, q.w), q.x),
        1 => (Vec3::new(q.x, q.z, q.w), q.y),
        2 => (Vec3::new(q.x, q.y, q.w), q.z),
        _ => (Vec3::new(q.x, q.y, q.z), q.w),
    };
    // |dropped| >= 1/2 for a unit quaternion, so its sign is never 0.
    let sign = if dropped < 0.0 { -1.0 } else { 1.0 };
    (three * (sign * FRAC_1_SQRT_2) + Vec3::splat(0.5)).extend(index as f32 / 3.0)
}

/// Appendix UnpackQuaternion. Deviation: the index is `round(w * 3)`, not a
/// truncation, so a unorm decode of 2/3 that lands at 1.9999 still reads 2.
pub fn unpack_quat(p: Vec4) -> Quat {
    let index = (p.w * 3.0).round() as i32;
    let three = p.truncate() * std::f32::consts::SQRT_2 - Vec3::splat(FRAC_1_SQRT_2);
    let dropped = (1.0 - three.length_squared().clamp(0.0, 1.0)).sqrt();
    let q = match index {
        0 => Vec4::new(dropped, three.x, three.y, three.z),
        1 => Vec4::new(three.x, dropped, three.y, three.z),
        2 => Vec4::new(three.x, three.y, dropped, three.z),
        _ => three.extend(dropped),
    };
    Quat::from_vec4(q)
}

/// What a store to an `Rgb10a2Unorm` target writes: clamp to \[0,1\], round to
/// nearest; x in bits 0..9, y 10..19, z 20..29, w 30..31.
pub fn quantize_rgb10a2(p: Vec4) -> u32 {
    let unorm = |v: f32, max: f32| (v.clamp(0.0, 1.0) * max + 0.5) as u32;
    unorm(p.x, 1023.0) | unorm(p.y, 1023.0) << 10 | unorm(p.z, 1023.0) << 20 | unorm(p.w, 3.0) << 30
}

/// What a load from an `Rgb10a2Unorm` texture returns.
pub fn dequantize_rgb10a2(bits: u32) -> Vec4 {
    Vec4::new(
        (bits & 1023) as f32 / 1023.0,
        ((bits >> 10) & 1023) as f32 / 1023.0,
        ((bits >> 20) & 1023) as f32 / 1023.0,
        (bits >> 30) as f32 / 3.0,
    )
}

/// Frame -> the 32 bits the G-buffer stores.
pub fn encode_frame(t: Vec3, b: Vec3, n: Vec3) -> u32 {
    quantize_rgb10a2(pack_quat(frame_to_quat(t, b, n)))
}

/// The 32 G-buffer bits -> frame (t, b, n).
pub fn decode_frame(bits: u32) -> (Vec3, Vec3, Vec3) {
    quat_to_frame(unpack_quat(dequantize_rgb10a2(bits)))
}

/// Some unit vector perpendicular to unit `n` (Duff et al. 2017).
fn any_perpendicular(n: Vec3) -> Vec3 {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    Vec3::new(
        1.0 + sign * n.x * n.x * a,
        sign * n.x * n.y * a,
        -sign * n.x,
    )
}

/// The right-handed shading frame the G-buffer stores: the vertex tangent
/// (glTF `TANGENT`, xyz + handedness w) Gram-Schmidt-orthogonalised against
/// the (normal-mapped) normal n, and b = cross(n, t). `tangent.w` is ignored
/// on purpose: see the module comment and [`apply_normal_map`]. A tangent
/// parallel to n (or zero) falls back to an arbitrary perpendicular.
pub fn shading_frame(n: Vec3, tangent: Vec4) -> (Vec3, Vec3, Vec3) {
    let n = n.normalize_or(Vec3::Z);
    let t_in = tangent.truncate();
    let t = (t_in - n * n.dot(t_in))
        .try_normalize()
        .unwrap_or_else(|| any_perpendicular(n));
    (t, n.cross(t), n)
}

/// Tangent-space normal (from a normal map, z up) -> world normal, with the
/// glTF bitangent cross(n, t) * tangent.w: this is where a mirrored frame's
/// sign is consumed, before [`shading_frame`] and packing.
pub fn apply_normal_map(n: Vec3, tangent: Vec4, ts_normal: Vec3) -> Vec3 {
    let (t, b, n) = shading_frame(n, tangent);
    let w = if tangent.w < 0.0 { -1.0 } else { 1.0 };
    (t * ts_normal.x + b * (w * ts_normal.y) + n * ts_normal.z).normalize_or(n)
}

/// Naive normal packing for the talk's comparison: n * 0.5 + 0.5 in 8:8:8
/// unorm, round to nearest.
pub fn encode_normal_888(n: Vec3) -> [u8; 3] {
    let q = |c: f32| ((c * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    [q(n.x), q(n.y), q(n.z)]
}

/// Inverse of [`encode_normal_888`], renormalised.
pub fn decode_normal_888(c: [u8; 3]) -> Vec3 {
    let d = |b: u8| b as f32 / 255.0 * 2.0 - 1.0;
    Vec3::new(d(c[0]), d(c[1]), d(c[2])).normalize_or(Vec3::Z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::brdf::{Surface, brdf_cos};
    use crate::math::sampling::{Pcg32, uniform_sample_sphere};
    use glam::{Mat3, Vec2};

    /// The appendix's TangentSpaceToQuaternion, verbatim.
    fn appendix_frame_to_quat(t: Vec3, b: Vec3, n: Vec3) -> Vec4 {
        Vec4::new(n.y - b.z, t.z - n.x, b.x - t.y, 1.0 + t.x + b.y + n.z).normalize()
    }

    /// The appendix's QuaternionToTangentSpace, verbatim (swizzles expanded).
    fn appendix_quat_to_frame(q: Vec4) -> (Vec3, Vec3, Vec3) {
        let t = Vec3::X
            + Vec3::new(-2.0, 2.0, 2.0) * q.y * Vec3::new(q.y, q.x, q.w)
            + Vec3::new(-2.0, -2.0, 2.0) * q.z * Vec3::new(q.z, q.w, q.x);
        let b = Vec3::Y
            + Vec3::new(2.0, -2.0, 2.0) * q.z * Vec3::new(q.w, q.z, q.y)
            + Vec3::new(2.0, -2.0, -2.0) * q.x * Vec3::new(q.y, q.x, q.w);
        let n = Vec3::Z
            + Vec3::new(2.0, 2.0, -2.0) * q.x * Vec3::new(q.z, q.w, q.x)
            + Vec3::new(-2.0, 2.0, -2.0) * q.y * Vec3::new(q.w, q.z, q.y);
        (t, b, n)
    }

    fn random_quat(rng: &mut Pcg32) -> Quat {
        // Shoemake 1992: uniform on the 3-sphere.
        let (u1, u2, u3) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
        let (s1, s2) = ((1.0 - u1).sqrt(), u1.sqrt());
        let (a, b) = (std::f32::consts::TAU * u2, std::f32::consts::TAU * u3);
        Quat::from_xyzw(s1 * a.sin(), s1 * a.cos(), s2 * b.sin(), s2 * b.cos())
    }

    fn cols(q: Quat) -> (Vec3, Vec3, Vec3) {
        let m = Mat3::from_quat(q);
        (m.x_axis, m.y_axis, m.z_axis)
    }

    #[test]
    fn frame_to_quat_inverts_glam_and_matches_the_appendix_where_it_can() {
        let mut rng = Pcg32::new(21);
        let (mut worst_glam, mut worst_appendix) = (0.0_f32, 0.0_f32);
        for i in 0..50_000 {
            let q = if i < 4 {
                // Exact 180-degree turns: the appendix's 0/0 cases.
                [
                    Quat::from_rotation_x(std::f32::consts::PI),
                    Quat::from_xyzw(0.0, 1.0, 0.0, 0.0),
                    Quat::from_xyzw(0.0, 0.0, 1.0, 0.0),
                    Quat::IDENTITY,
                ][i]
            } else {
                random_quat(&mut rng)
            };
            let (t, b, n) = cols(q);
            let ours = Vec4::from(frame_to_quat(t, b, n));
            // Same rotation as glam's, up to the sign of the quaternion.
            worst_glam = worst_glam.max(1.0 - ours.dot(Vec4::from(q)).abs());
            // Well-conditioned for the appendix: w = 1 + trace >= 0.5.
            if 1.0 + t.x + b.y + n.z >= 0.5 {
                let conj = Vec4::new(-ours.x, -ours.y, -ours.z, ours.w);
                let appendix = appendix_frame_to_quat(t, b, n);
                worst_appendix =
                    worst_appendix.max((appendix - conj * ours.w.signum()).abs().max_element());
                // Its decoder on its quaternion gives back the frame, and ours on
                // ours: the two conventions are conjugates of one another.
                let (at, ab, an) = appendix_quat_to_frame(appendix);
                let (ot, ob, on) = quat_to_frame(Quat::from_vec4(ours));
                for (x, y) in [(at, t), (ab, b), (an, n), (ot, t), (ob, b), (on, n)] {
                    assert!((x - y).abs().max_element() < 1e-5, "{x} vs {y}");
                }
            }
        }
        println!(
            "frame_to_quat: worst 1 - |q.q_glam| {worst_glam:.1e}, worst |appendix - conj| {worst_appendix:.1e}"
        );
        // Measured 1.8e-7 and 4.2e-7 on 2026-11-22 (f32 rounding); threshold 1e-5.
        assert!(
            worst_glam < 1e-5 && worst_appendix < 1e-5,
            "{worst_glam} {worst_appendix}"
        );
    }

    #[test]
    fn appendix_formula_is_singular_at_half_turns() {
        // The reason for Shepperd's branches: trace = -1 gives 0/0.
        let (t, b, n) = cols(Quat::from_xyzw(0.0, 1.0, 0.0, 0.0));
        assert!(appendix_frame_to_quat(t, b, n).is_nan());
        assert!(Vec4::from(frame_to_quat(t, b, n)).is_finite());
    }

    #[test]
    fn dropped_component_reconstructs_positive() {
        let mut rng = Pcg32::new(22);
        for _ in 0..20_000 {
            let q = Vec4::from(random_quat(&mut rng));
            let packed = pack_quat(Quat::from_vec4(q));
            assert!(packed.min_element() >= -1e-6 && packed.max_element() <= 1.0 + 1e-6);
            let index = largest_component(q);
            let sign = q[index].signum();
            let unpacked = Vec4::from(unpack_quat(packed));
            assert!(unpacked[index] > 0.0);
            assert!(
                (unpacked - q * sign).abs().max_element() < 1e-5,
                "{q} -> {unpacked}"
            );
        }
    }

    #[test]
    fn rgb10a2_bit_layout_and_rounding() {
        assert_eq!(quantize_rgb10a2(Vec4::new(1.0, 0.0, 0.0, 0.0)), 0x3ff);
        assert_eq!(quantize_rgb10a2(Vec4::new(0.0, 1.0, 0.0, 0.0)), 0x3ff << 10);
        assert_eq!(quantize_rgb10a2(Vec4::new(0.0, 0.0, 1.0, 0.0)), 0x3ff << 20);
        assert_eq!(quantize_rgb10a2(Vec4::new(0.0, 0.0, 0.0, 1.0)), 3 << 30);
        assert_eq!(
            quantize_rgb10a2(Vec4::new(0.4995 / 1023.0, 0.5005 / 1023.0, -3.0, 2.0 / 3.0)),
            1 << 10 | 2 << 30
        );
        for bits in [0, 1, 0x3ff, 0x1234_5678, u32::MAX] {
            assert_eq!(quantize_rgb10a2(dequantize_rgb10a2(bits)), bits);
        }
    }

    #[test]
    fn mirrored_tangent_encodes_like_its_unmirrored_twin() {
        let mut rng = Pcg32::new(23);
        for _ in 0..10_000 {
            let n = uniform_sample_sphere(rng.next_vec2());
            let t = uniform_sample_sphere(rng.next_vec2());
            let right = shading_frame(n, t.extend(1.0));
            let mirrored = shading_frame(n, t.extend(-1.0));
            assert_eq!(right, mirrored);
            let (ft, fb, fn_) = right;
            assert!((ft.cross(fb).dot(fn_) - 1.0).abs() < 1e-5, "right-handed");
            let (dt, _, dn) = decode_frame(encode_frame(ft, fb, fn_));
            // Quantisation only: about 0.2 degrees (see the 100k-frame test).
            assert!(dt.dot(ft) > 0.999_99 && dn.dot(fn_) > 0.999_99);
            // The sign is consumed by normal mapping instead.
            let ts = Vec3::new(0.3, 0.4, 0.866).normalize();
            let flipped = apply_normal_map(n, t.extend(-1.0), ts);
            let expected = (ft * ts.x - fb * ts.y + fn_ * ts.z).normalize();
            assert!((flipped - expected).length() < 1e-5);
        }
        // Degenerate tangents still give an orthonormal frame.
        for tangent in [
            Vec4::ZERO,
            Vec4::new(0.0, 0.0, 2.0, 1.0),
            Vec4::new(0.0, 0.0, -1.0, -1.0),
        ] {
            let (t, b, n) = shading_frame(Vec3::Z, tangent);
            assert!(t.dot(n).abs() < 1e-6 && (t.cross(b).dot(n) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn lighting_is_invariant_under_binormal_flip() {
        // Why no G-buffer bit is spent on handedness: D and V see (h.b)^2,
        // (v.b)^2, (l.b)^2, and M4's aN = cross(cross(v, b), b) is even in b.
        let mut rng = Pcg32::new(24);
        for i in 0..20_000 {
            let n = uniform_sample_sphere(rng.next_vec2());
            let (t, b, _) = shading_frame(n, uniform_sample_sphere(rng.next_vec2()).extend(1.0));
            let (v, l) = (
                uniform_sample_sphere(rng.next_vec2()),
                uniform_sample_sphere(rng.next_vec2()),
            );
            let alpha = Vec2::new(0.002 + rng.next_f32(), 0.002 + rng.next_f32());
            let s = Surface {
                diffuse_albedo: Vec3::splat((i % 2) as f32),
                f0: Vec3::splat(0.04),
                alpha,
                alpha_v: alpha,
            };
            assert_eq!(brdf_cos(&s, t, b, n, v, l), brdf_cos(&s, t, -b, n, v, l));
            let aniso_normal = |b: Vec3| v.cross(b).cross(b);
            assert_eq!(aniso_normal(b), aniso_normal(-b));
        }
    }
}
