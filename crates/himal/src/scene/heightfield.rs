//! Height fields: a regular grid of heights from seeded noise or a 16-bit
//! PNG, meshed with central-difference normals and material layers blended
//! per vertex by height and slope.

use std::path::Path;

use glam::Vec3;

use super::noise::{self, Fractal};
use super::primitives::MeshBuilder;
use super::{MaterialDesc, Mesh};

/// Seeded mountain-valley generator. All lengths in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainNoise {
    /// Seed of the noise (same seed, same terrain).
    pub seed: u32,
    /// Number of noise octaves summed (more = finer detail).
    pub octaves: u32,
    /// Base frequency in cycles per metre (1/200 gives features about 200 m wide).
    pub frequency: f32,
    /// Height scale of the mountains in metres; the highest peaks reach about this.
    pub amplitude: f32,
    /// Ridged multifractal (sharp crests, [`noise::ridged`]) instead of eroded fBm (rounded hills).
    pub ridged: bool,
    /// Frequency multiplier between octaves (2 doubles the frequency each octave).
    pub lacunarity: f32,
    /// Amplitude multiplier between octaves (0.5 halves each octave).
    pub gain: f32,
    /// Domain warp in metres: bends ridges and the valley's outline.
    pub warp: f32,
    /// Damps detail on steep slopes (0 = plain fBm), [`noise::eroded_fbm`].
    pub erosion: f32,
    /// Within this distance of the local origin the mountains are absent...
    pub flat_radius: f32,
    /// ...and from this distance on they have their full height.
    pub valley_radius: f32,
    /// Gentle undulation of the valley floor (damped to a fifth inside `flat_radius`).
    pub floor_amplitude: f32,
}

impl Default for TerrainNoise {
    fn default() -> Self {
        TerrainNoise {
            seed: 1,
            octaves: 8,
            frequency: 1.0 / 400.0,
            amplitude: 100.0,
            ridged: true,
            lacunarity: 2.0,
            gain: 0.5,
            warp: 0.0,
            erosion: 0.0,
            flat_radius: 0.0,
            valley_radius: 0.0,
            floor_amplitude: 0.0,
        }
    }
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    if e1 <= e0 {
        return if x < e0 { 0.0 } else { 1.0 };
    }
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl TerrainNoise {
    /// Height in metres at local (x, z); a pure function of the parameters.
    pub fn height(&self, x: f32, z: f32) -> f32 {
        let f = self.frequency;
        let fractal = Fractal {
            octaves: self.octaves,
            lacunarity: self.lacunarity,
            gain: self.gain,
        };
        let smooth = Fractal {
            octaves: 3,
            ..Fractal::default()
        };
        let seed = self.seed.wrapping_mul(0x9e37_79b9);
        let (wx, wz) = if self.warp != 0.0 {
            let qx = noise::fbm(seed ^ 0x51ed_270b, x * f * 0.5, z * f * 0.5, smooth);
            let qz = noise::fbm(
                seed ^ 0x2f1c_3a55,
                x * f * 0.5 + 5.2,
                z * f * 0.5 + 1.3,
                smooth,
            );
            (x + self.warp * qx, z + self.warp * qz)
        } else {
            (x, z)
        };
        let shape = if self.ridged {
            noise::ridged(seed, wx * f, wz * f, fractal, self.erosion)
        } else {
            0.5 + 0.5 * noise::eroded_fbm(seed, wx * f, wz * f, fractal, self.erosion)
        };
        // Broad variation so some massifs stand higher than others.
        let massif = 0.5 + 0.5 * noise::fbm(seed ^ 0x1b87_3593, wx * f * 0.6, wz * f * 0.6, smooth);
        let mask = if self.valley_radius > 0.0 {
            let d = (wx * wx + wz * wz).sqrt();
            let s = smoothstep(self.flat_radius, self.valley_radius, d);
            s * s
        } else {
            1.0
        };
        let mountains = mask * (0.15 + 0.85 * shape) * (0.5 + 0.8 * massif);
        let floor = if self.floor_amplitude != 0.0 {
            let d = (x * x + z * z).sqrt();
            let calm = 0.2 + 0.8 * smoothstep(self.flat_radius * 0.5, self.flat_radius, d);
            let n = noise::fbm(seed ^ 0x6a09_e667, x * f * 2.0, z * f * 2.0, smooth);
            self.floor_amplitude * calm * n
        } else {
            0.0
        };
        self.amplitude * mountains + floor
    }
}

/// A material painted over the terrain where height and slope fall in its ranges.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainLayer {
    /// The material painted where the layer covers.
    pub material: MaterialDesc,
    /// Lowest height in metres the layer covers (`-inf`: no limit).
    pub min_height: f32,
    /// Highest height in metres the layer covers (`inf`: no limit).
    pub max_height: f32,
    /// Slope angles in degrees from horizontal (0 = flat, 90 = vertical).
    pub min_slope: f32,
    /// Steepest slope covered, in degrees from horizontal (90 = no limit).
    pub max_slope: f32,
    /// Width in metres of the transition at each height limit.
    pub blend: f32,
    /// Width in degrees of the transition at each slope limit.
    pub slope_blend: f32,
    /// Amplitude in metres of noise added to the height before the test, so
    /// borders (e.g. the snow line) are ragged instead of contour lines.
    pub jitter: f32,
}

impl TerrainLayer {
    /// A layer of `material` covering every height and slope, with hard edges and no jitter.
    pub fn new(material: MaterialDesc) -> Self {
        TerrainLayer {
            material,
            min_height: f32::NEG_INFINITY,
            max_height: f32::INFINITY,
            min_slope: 0.0,
            max_slope: 90.0,
            blend: 0.0,
            slope_blend: 0.0,
            jitter: 0.0,
        }
    }

    /// Coverage in [0, 1]: smooth band in height times smooth band in slope.
    /// Slope limits at 0 and 90 degrees mean "no limit" (no blend there).
    pub fn coverage(&self, height: f32, slope_deg: f32) -> f32 {
        let min_slope = if self.min_slope > 0.0 {
            self.min_slope
        } else {
            f32::NEG_INFINITY
        };
        let max_slope = if self.max_slope < 90.0 {
            self.max_slope
        } else {
            f32::INFINITY
        };
        band(height, self.min_height, self.max_height, self.blend)
            * band(slope_deg, min_slope, max_slope, self.slope_blend)
    }
}

/// 1 inside [lo, hi], 0 outside, with smoothstep edges `width` wide.
pub(crate) fn band(x: f32, lo: f32, hi: f32, width: f32) -> f32 {
    let w = width * 0.5;
    let above_lo = if lo.is_finite() {
        smoothstep(lo - w, lo + w, x)
    } else {
        1.0
    };
    let below_hi = if hi.is_finite() {
        1.0 - smoothstep(hi - w, hi + w, x)
    } else {
        1.0
    };
    above_lo * below_hi
}

/// Heights on an `nx` x `nz` grid covering `size` = [x, z] metres centred on
/// the local origin; row-major with z (rows) outer, x (columns) inner.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightGrid {
    /// Grid columns along x (at least 2).
    pub nx: usize,
    /// Grid rows along z (at least 2).
    pub nz: usize,
    /// Extent along x and z in metres; vertices span -size/2..size/2.
    pub size: [f32; 2],
    /// `nx * nz` heights in metres, row-major (row j = z index, outer).
    pub heights: Vec<f32>,
}

impl HeightGrid {
    /// Samples `f(x, z)` (local metres) at every grid vertex.
    pub fn from_fn(size: [f32; 2], nx: usize, nz: usize, f: impl Fn(f32, f32) -> f32) -> Self {
        let mut g = HeightGrid {
            nx,
            nz,
            size,
            heights: Vec::with_capacity(nx * nz),
        };
        for j in 0..nz {
            for i in 0..nx {
                let (x, z) = g.grid_xz(i, j);
                g.heights.push(f(x, z));
            }
        }
        g
    }

    /// A `resolution` x `resolution` grid of [`TerrainNoise::height`].
    pub fn from_noise(size: [f32; 2], resolution: usize, noise: &TerrainNoise) -> Self {
        Self::from_fn(size, resolution, resolution, |x, z| noise.height(x, z))
    }

    /// Width and height of the image at `path`, read from its header only.
    pub fn png_dimensions(path: &Path) -> Result<(u32, u32), String> {
        image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| e.to_string())?
            .into_dimensions()
            .map_err(|e| e.to_string())
    }

    /// Heights from a grayscale image (any bit depth, 16-bit recommended):
    /// white = `height_scale` metres. Column 0 is at -x, row 0 at -z.
    /// `resolution` resamples bilinearly; `None` keeps one vertex per pixel.
    pub fn from_png(
        path: &Path,
        size: [f32; 2],
        height_scale: f32,
        resolution: Option<usize>,
    ) -> Result<Self, String> {
        let img = image::open(path).map_err(|e| e.to_string())?.to_luma16();
        let (w, h) = (img.width() as usize, img.height() as usize);
        if w < 2 || h < 2 {
            return Err(format!("image is {w}x{h} pixels; at least 2x2 needed"));
        }
        let pixel = |x: usize, y: usize| img.get_pixel(x as u32, y as u32).0[0] as f32 / 65535.0;
        let (nx, nz) = resolution.map_or((w, h), |r| (r, r));
        let mut g = HeightGrid {
            nx,
            nz,
            size,
            heights: Vec::with_capacity(nx * nz),
        };
        for j in 0..nz {
            let fy = j as f32 / (nz - 1) as f32 * (h - 1) as f32;
            let (y0, ty) = (
                (fy as usize).min(h - 2),
                fy - (fy as usize).min(h - 2) as f32,
            );
            for i in 0..nx {
                let fx = i as f32 / (nx - 1) as f32 * (w - 1) as f32;
                let (x0, tx) = (
                    (fx as usize).min(w - 2),
                    fx - (fx as usize).min(w - 2) as f32,
                );
                let top = pixel(x0, y0) * (1.0 - tx) + pixel(x0 + 1, y0) * tx;
                let bottom = pixel(x0, y0 + 1) * (1.0 - tx) + pixel(x0 + 1, y0 + 1) * tx;
                g.heights
                    .push((top * (1.0 - ty) + bottom * ty) * height_scale);
            }
        }
        Ok(g)
    }

    fn spacing(&self) -> (f32, f32) {
        (
            self.size[0] / (self.nx - 1) as f32,
            self.size[1] / (self.nz - 1) as f32,
        )
    }

    fn grid_xz(&self, i: usize, j: usize) -> (f32, f32) {
        (
            (i as f32 / (self.nx - 1) as f32 - 0.5) * self.size[0],
            (j as f32 / (self.nz - 1) as f32 - 0.5) * self.size[1],
        )
    }

    /// Height in metres at column `i < nx`, row `j < nz`.
    pub fn h(&self, i: usize, j: usize) -> f32 {
        self.heights[j * self.nx + i]
    }

    /// Normal from central differences (one-sided at the borders).
    pub fn normal(&self, i: usize, j: usize) -> Vec3 {
        let (dx, dz) = self.spacing();
        let (i0, i1) = (i.saturating_sub(1), (i + 1).min(self.nx - 1));
        let (j0, j1) = (j.saturating_sub(1), (j + 1).min(self.nz - 1));
        let dhdx = (self.h(i1, j) - self.h(i0, j)) / ((i1 - i0) as f32 * dx);
        let dhdz = (self.h(i, j1) - self.h(i, j0)) / ((j1 - j0) as f32 * dz);
        Vec3::new(-dhdx, 1.0, -dhdz).normalize()
    }

    /// Height of the meshed surface at local (x, z), interpolated on the same
    /// two triangles per cell as the mesh; `None` outside the grid.
    pub fn height_at(&self, x: f32, z: f32) -> Option<f32> {
        let fx = (x / self.size[0] + 0.5) * (self.nx - 1) as f32;
        let fz = (z / self.size[1] + 0.5) * (self.nz - 1) as f32;
        let eps = 1e-4;
        let (max_x, max_z) = ((self.nx - 1) as f32 + eps, (self.nz - 1) as f32 + eps);
        // Written so NaN coordinates also land outside.
        if !(fx >= -eps && fx <= max_x && fz >= -eps && fz <= max_z) {
            return None;
        }
        let i = (fx.max(0.0) as usize).min(self.nx - 2);
        let j = (fz.max(0.0) as usize).min(self.nz - 2);
        let (tx, tz) = (fx - i as f32, fz - j as f32);
        let (a, b) = (self.h(i, j), self.h(i + 1, j));
        let (c, d) = (self.h(i, j + 1), self.h(i + 1, j + 1));
        Some(if tx + tz <= 1.0 {
            a + tx * (b - a) + tz * (c - a)
        } else {
            d + (1.0 - tx) * (c - d) + (1.0 - tz) * (b - d)
        })
    }

    /// Triangle mesh; `layers[0]` is the base and covers everything, later
    /// layers are painted over in order with their coverage (all vertex
    /// colour and surface fields blended). `albedo_variation` scales albedo
    /// by 1 +- that fraction with low-frequency noise so large fields are not flat.
    pub fn mesh(
        &self,
        name: String,
        layers: &[TerrainLayer],
        seed: u32,
        albedo_variation: f32,
    ) -> Mesh {
        let base = layers
            .first()
            .map_or_else(MaterialDesc::default, |l| l.material.clone());
        let mut b = MeshBuilder::new(&base);
        let jitter = Fractal {
            octaves: 4,
            ..Fractal::default()
        };
        for j in 0..self.nz {
            for i in 0..self.nx {
                let (x, z) = self.grid_xz(i, j);
                let h = self.h(i, j);
                let n = self.normal(i, j);
                let slope = n.y.clamp(-1.0, 1.0).acos().to_degrees();
                let mut color = Vec3::from_slice(&base.vertex_color()).extend(base.ao);
                let mut surface = glam::Vec4::from(base.vertex_surface());
                for (k, layer) in layers.iter().enumerate().skip(1) {
                    let hj = if layer.jitter != 0.0 {
                        let s = seed.wrapping_add(0x3c6e_f372).wrapping_add(k as u32);
                        h + layer.jitter * noise::fbm(s, x / 40.0, z / 40.0, jitter)
                    } else {
                        h
                    };
                    let w = layer.coverage(hj, slope);
                    if w > 0.0 {
                        let m = &layer.material;
                        color = color.lerp(glam::Vec4::from(m.vertex_color()), w);
                        surface = surface.lerp(glam::Vec4::from(m.vertex_surface()), w);
                    }
                }
                if albedo_variation != 0.0 {
                    let v = noise::fbm(seed ^ 0xbb67_ae85, x / 25.0, z / 25.0, jitter);
                    let k = 1.0 + albedo_variation * v;
                    color = (color.truncate() * k)
                        .clamp(Vec3::ZERO, Vec3::ONE)
                        .extend(color.w);
                }
                // Tangent: +X projected onto the tangent plane (never parallel to n here).
                let t = (Vec3::X - n * n.x).normalize();
                let v = b.vertex(Vec3::new(x, h, z), n, t, [x, -z]);
                b.paint(v, color.to_array(), surface.to_array());
            }
        }
        let row = self.nx as u32;
        for j in 0..self.nz as u32 - 1 {
            for i in 0..row - 1 {
                let a = j * row + i;
                // Same diagonal as `height_at`: (i+1, j) to (i, j+1).
                b.triangle(a, a + row, a + 1);
                b.triangle(a + 1, a + row, a + row + 1);
            }
        }
        b.finish(name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn height_at_follows_the_mesh_triangles() {
        let g = HeightGrid::from_fn([30.0, 20.0], 4, 3, |x, z| {
            (x * 0.3).sin() * 4.0 + z * z * 0.05
        });
        // Exact at grid points.
        for j in 0..3 {
            for i in 0..4 {
                let (x, z) = g.grid_xz(i, j);
                assert!((g.height_at(x, z).unwrap_or(f32::NAN) - g.h(i, j)).abs() < 1e-5);
            }
        }
        // Inside the first cell's two triangles: planar through their corners.
        let (x0, z0) = g.grid_xz(0, 0);
        let (dx, dz) = g.spacing();
        let (a, b, c, d) = (g.h(0, 0), g.h(1, 0), g.h(0, 1), g.h(1, 1));
        let lower = g
            .height_at(x0 + 0.25 * dx, z0 + 0.5 * dz)
            .unwrap_or(f32::NAN);
        assert!((lower - (a + 0.25 * (b - a) + 0.5 * (c - a))).abs() < 1e-5);
        let upper = g
            .height_at(x0 + 0.75 * dx, z0 + 0.5 * dz)
            .unwrap_or(f32::NAN);
        assert!((upper - (d + 0.25 * (c - d) + 0.5 * (b - d))).abs() < 1e-5);
        assert!(g.height_at(15.1, 0.0).is_none() && g.height_at(0.0, -10.1).is_none());
        assert!(g.height_at(f32::NAN, 0.0).is_none());
    }

    #[test]
    fn layer_coverage_is_smooth_and_banded() {
        let mut l = TerrainLayer::new(MaterialDesc::default());
        l.min_height = 100.0;
        l.blend = 20.0;
        l.max_slope = 40.0;
        l.slope_blend = 10.0;
        assert_eq!(l.coverage(80.0, 0.0), 0.0);
        assert!((l.coverage(100.0, 0.0) - 0.5).abs() < 1e-6);
        assert_eq!(l.coverage(120.0, 0.0), 1.0);
        assert!((l.coverage(120.0, 40.0) - 0.5).abs() < 1e-6);
        assert_eq!(l.coverage(120.0, 46.0), 0.0);
        // Unlimited ends do not blend: full coverage on flat ground and at 90 degrees.
        l.max_slope = 90.0;
        assert_eq!(l.coverage(120.0, 90.0), 1.0);
    }
}
