//! Deterministic 2D gradient noise, fBm and ridged multifractal.
//!
//! Everything here is a pure function of `(seed, x, z)`: no tables, no
//! global state, no platform-dependent transcendental functions on the hot
//! path (gradients come from a fixed table), so the same seed gives the same
//! terrain on every machine.

/// Unit gradients at 22.5 degree steps; a table keeps `sin`/`cos` (whose last
/// bits may differ between libms) out of the result.
const GRADIENTS: [[f32; 2]; 16] = {
    const A: f32 = 0.923_879_5; // cos 22.5
    const B: f32 = 0.707_106_77; // cos 45
    const C: f32 = 0.382_683_43; // cos 67.5
    [
        [1.0, 0.0],
        [A, C],
        [B, B],
        [C, A],
        [0.0, 1.0],
        [-C, A],
        [-B, B],
        [-A, C],
        [-1.0, 0.0],
        [-A, -C],
        [-B, -B],
        [-C, -A],
        [0.0, -1.0],
        [C, -A],
        [B, -B],
        [A, -C],
    ]
};

/// 2D Perlin gradient noise peaks at sqrt(1/2); this scales it to about [-1, 1].
const GRADIENT_NOISE_SCALE: f32 = std::f32::consts::SQRT_2;

/// murmur3's 32-bit finaliser: a cheap full-avalanche mix.
fn fmix32(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 16;
    h
}

/// Hash of a lattice point; chained mixing so (x, z) and (z, x) differ.
pub fn hash_lattice(seed: u32, ix: i32, iz: i32) -> u32 {
    let h = fmix32(seed ^ 0x27d4_eb2d);
    let h = fmix32(h ^ (ix as u32).wrapping_mul(0x9e37_79b9));
    fmix32(h ^ (iz as u32).wrapping_mul(0x85eb_ca6b))
}

/// Uniform value in [0, 1) from a hash.
pub fn hash_to_unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

fn quintic(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn quintic_derivative(t: f32) -> f32 {
    30.0 * t * t * (t * (t - 2.0) + 1.0)
}

/// Gradient noise in about [-1, 1] and its analytic derivative (d/dx, d/dz).
pub fn gradient_noise_d(seed: u32, x: f32, z: f32) -> (f32, [f32; 2]) {
    let (xf, zf) = (x.floor(), z.floor());
    let (ix, iz) = (xf as i32, zf as i32);
    let (fx, fz) = (x - xf, z - zf);
    let grad = |dx: i32, dz: i32| GRADIENTS[(hash_lattice(seed, ix + dx, iz + dz) >> 28) as usize];
    let (ga, gb, gc, gd) = (grad(0, 0), grad(1, 0), grad(0, 1), grad(1, 1));
    let va = ga[0] * fx + ga[1] * fz;
    let vb = gb[0] * (fx - 1.0) + gb[1] * fz;
    let vc = gc[0] * fx + gc[1] * (fz - 1.0);
    let vd = gd[0] * (fx - 1.0) + gd[1] * (fz - 1.0);
    let (ux, uz) = (quintic(fx), quintic(fz));
    let (dux, duz) = (quintic_derivative(fx), quintic_derivative(fz));
    let k = va - vb - vc + vd;
    let value = va + ux * (vb - va) + uz * (vc - va) + ux * uz * k;
    let mut d = [0.0; 2];
    for (i, di) in d.iter_mut().enumerate() {
        *di = ga[i]
            + ux * (gb[i] - ga[i])
            + uz * (gc[i] - ga[i])
            + ux * uz * (ga[i] - gb[i] - gc[i] + gd[i]);
    }
    d[0] += dux * (vb - va + uz * k);
    d[1] += duz * (vc - va + ux * k);
    (
        value * GRADIENT_NOISE_SCALE,
        [d[0] * GRADIENT_NOISE_SCALE, d[1] * GRADIENT_NOISE_SCALE],
    )
}

/// Gradient noise in about [-1, 1].
pub fn gradient_noise(seed: u32, x: f32, z: f32) -> f32 {
    gradient_noise_d(seed, x, z).0
}

/// Octave parameters shared by the fractal sums.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fractal {
    /// Number of noise octaves summed (0 counts as 1).
    pub octaves: u32,
    /// Frequency multiplier between octaves.
    pub lacunarity: f32,
    /// Amplitude multiplier between octaves.
    pub gain: f32,
}

impl Default for Fractal {
    fn default() -> Self {
        Fractal {
            octaves: 6,
            lacunarity: 2.0,
            gain: 0.5,
        }
    }
}

/// Rotates each octave by about 36.87 degrees (a 3-4-5 triangle, exact in
/// f32) so lattice axes of successive octaves do not line up.
fn rotate_octave(x: f32, z: f32) -> (f32, f32) {
    (0.8 * x - 0.6 * z, 0.6 * x + 0.8 * z)
}

/// Fractional Brownian motion of gradient noise, normalised to about [-1, 1].
pub fn fbm(seed: u32, x: f32, z: f32, f: Fractal) -> f32 {
    let (mut px, mut pz) = (x, z);
    let (mut sum, mut amp, mut norm) = (0.0, 1.0, 0.0);
    for octave in 0..f.octaves.max(1) {
        sum += amp * gradient_noise(seed.wrapping_add(octave), px, pz);
        norm += amp;
        amp *= f.gain;
        (px, pz) = rotate_octave(px * f.lacunarity, pz * f.lacunarity);
    }
    sum / norm
}

/// fBm whose octaves are damped where the sum is already steep
/// (Quilez's "derivative" terrain): slopes stay smooth and valleys gather
/// detail, which reads as erosion. `erosion` = 0 gives plain fBm. About [-1, 1].
pub fn eroded_fbm(seed: u32, x: f32, z: f32, f: Fractal, erosion: f32) -> f32 {
    let (mut px, mut pz) = (x, z);
    let (mut sum, mut amp, mut norm) = (0.0, 1.0, 0.0);
    // Running derivative in the unrotated frame scaled per octave.
    let (mut dx, mut dz) = (0.0, 0.0);
    let (mut ca, mut sa) = (1.0f32, 0.0f32);
    let mut freq = 1.0;
    for octave in 0..f.octaves.max(1) {
        let (n, d) = gradient_noise_d(seed.wrapping_add(octave), px, pz);
        // Chain rule back to world axes: rotation (ca, sa) and scale freq.
        let wx = (d[0] * ca + d[1] * sa) * freq;
        let wz = (-d[0] * sa + d[1] * ca) * freq;
        dx += amp * wx;
        dz += amp * wz;
        sum += amp * n / (1.0 + erosion * (dx * dx + dz * dz));
        norm += amp;
        amp *= f.gain;
        freq *= f.lacunarity;
        (ca, sa) = (0.8 * ca - 0.6 * sa, 0.6 * ca + 0.8 * sa);
        (px, pz) = rotate_octave(px * f.lacunarity, pz * f.lacunarity);
    }
    sum / norm
}

/// Ridged multifractal: sharp crests where an eroded fBm crosses zero,
/// `(1 - 1.5 |eroded_fbm|)^2`, about [0, 1]. Musgrave's per-octave ridges
/// close into crater-like rings around every extremum of the first octave
/// at the scale of a 1 km valley; ridging the (eroded) sum keeps the crests
/// long and branching and the valleys between them smooth.
pub fn ridged(seed: u32, x: f32, z: f32, f: Fractal, erosion: f32) -> f32 {
    let n = eroded_fbm(seed, x, z, f, erosion);
    let r = (1.0 - 1.5 * n.abs()).max(0.0);
    r * r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_noise_is_deterministic_bounded_and_seeded() {
        let mut max = 0.0f32;
        let mut differs = 0;
        for i in 0..20_000 {
            let x = (i % 200) as f32 * 0.173 - 13.0;
            let z = (i / 200) as f32 * 0.219 - 7.0;
            let a = gradient_noise(3, x, z);
            assert_eq!(a.to_bits(), gradient_noise(3, x, z).to_bits());
            if (a - gradient_noise(4, x, z)).abs() > 1e-3 {
                differs += 1;
            }
            max = max.max(a.abs());
        }
        eprintln!("gradient noise max |n| {max}");
        // Measured max |n| = 0.93 on 2026-11-22 (theoretical bound 1.0).
        assert!(max <= 1.0 && max > 0.6, "max |noise| {max}");
        assert!(differs > 19_000, "seed changes too little: {differs}");
    }

    #[test]
    fn analytic_derivative_matches_finite_differences() {
        let h = 1e-3;
        let mut worst = 0.0f32;
        for i in 0..500 {
            let x = i as f32 * 0.0371 + 0.013;
            let z = i as f32 * 0.0529 - 3.3;
            let (_, d) = gradient_noise_d(9, x, z);
            let fx = (gradient_noise(9, x + h, z) - gradient_noise(9, x - h, z)) / (2.0 * h);
            let fz = (gradient_noise(9, x, z + h) - gradient_noise(9, x, z - h)) / (2.0 * h);
            worst = worst.max((d[0] - fx).abs()).max((d[1] - fz).abs());
        }
        eprintln!("derivative error {worst}");
        // Measured 0.0012 on 2026-11-22 (f32 finite differences); threshold 0.01.
        assert!(worst < 0.01, "derivative error {worst}");
    }

    #[test]
    fn fractals_stay_in_their_ranges() {
        let f = Fractal {
            octaves: 8,
            ..Fractal::default()
        };
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        let (mut rlo, mut rhi) = (f32::MAX, f32::MIN);
        for i in 0..10_000 {
            let x = (i % 100) as f32 * 0.071;
            let z = (i / 100) as f32 * 0.067;
            let v = fbm(1, x, z, f);
            let e = eroded_fbm(1, x, z, f, 1.0);
            let r = ridged(1, x, z, f, 0.6);
            lo = lo.min(v).min(e);
            hi = hi.max(v).max(e);
            rlo = rlo.min(r);
            rhi = rhi.max(r);
        }
        eprintln!("fbm/eroded [{lo}, {hi}], ridged [{rlo}, {rhi}]");
        // Measured fbm/eroded in [-0.58, 0.54], ridged in [0.079, 1.0] on 2026-11-22.
        assert!(lo >= -1.0 && hi <= 1.0 && hi - lo > 0.5, "fbm [{lo}, {hi}]");
        assert!(
            rlo >= 0.0 && rhi <= 1.0 && rhi - rlo > 0.5,
            "ridged [{rlo}, {rhi}]"
        );
    }
}
