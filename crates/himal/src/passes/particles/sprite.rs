//! E4 normal-mapped sprites: the built-in "puff" (a cauliflower of
//! spherical caps with a little value noise, generated here,
//! deterministically) and scene-file images, as layers of one RGBA8 array
//! with its mip chain. A texel holds the sprite's tangent-space normal
//! (x right, y up, z toward the camera; n/2 + 1/2) and its opacity.
//! `forward.particles` samples it (`particle_sprite_rotate`,
//! `particle_sprite_normal_mapped`). Math: `docs/techniques/E4.md`.

use glam::{Vec2, Vec3};

use std::sync::Arc;

use super::reference::pcg;
pub use crate::scene::SPRITE_SIZE;
use crate::scene::{EmitterDesc, Sprite, SpriteImage};

/// The sprite's texture format: the normal and opacity are linear data.
pub const SPRITE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// A number in [0, 1) from an integer lattice point and a seed.
fn lattice(x: i32, y: i32, seed: u32) -> f32 {
    let h = pcg(pcg(x as u32 ^ pcg(y as u32)) ^ seed);
    (h >> 8) as f32 / 16_777_216.0
}

/// Smooth value noise in [0, 1): the lattice bilinearly blended with a
/// smoothstep.
fn value_noise(p: Vec2, seed: u32) -> f32 {
    let (i, f) = (p.floor(), p - p.floor());
    let s = f * f * (Vec2::splat(3.0) - 2.0 * f);
    let (x, y) = (i.x as i32, i.y as i32);
    let a = lattice(x, y, seed) + (lattice(x + 1, y, seed) - lattice(x, y, seed)) * s.x;
    let b = lattice(x, y + 1, seed) + (lattice(x + 1, y + 1, seed) - lattice(x, y + 1, seed)) * s.x;
    a + (b - a) * s.y
}

/// The puff's height over the sprite square, p in [-1, 1]² (y up): the
/// highest of a few spherical caps sqrt(r² − |p − c|²) (a cauliflower of
/// billows), with three octaves of value noise on top where it stands.
pub fn puff_height(p: Vec2) -> f32 {
    // Caps: one in the middle, a ring of six, a ring of small ones; centres
    // and radii jittered from a fixed seed.
    let mut h = 0.0f32;
    let mut cap = |c: Vec2, r: f32| {
        let d2 = (p - c).length_squared();
        h = h.max((r * r - d2).max(0.0).sqrt());
    };
    cap(Vec2::new(0.0, -0.05), 0.5);
    for k in 0..6u32 {
        let j = |n: u32| lattice(k as i32, n as i32, 17) - 0.5;
        let a = std::f32::consts::TAU * (k as f32 + 0.3 * j(0)) / 6.0;
        let c = Vec2::from_angle(a) * (0.38 + 0.12 * j(1));
        cap(c, 0.3 + 0.1 * j(2));
    }
    for k in 0..9u32 {
        let j = |n: u32| lattice(k as i32, n as i32, 29) - 0.5;
        let a = std::f32::consts::TAU * (k as f32 + 0.5 + 0.4 * j(0)) / 9.0;
        let c = Vec2::from_angle(a) * (0.62 + 0.1 * j(1));
        cap(c, 0.17 + 0.06 * j(2));
    }
    if h <= 0.0 {
        return 0.0;
    }
    let mut noise = 0.0;
    let mut amp = 0.5;
    for octave in 0..3u32 {
        let f = 4.0 * (1 << octave) as f32;
        noise += amp * (value_noise(p * f, 101 + octave) - 0.5);
        amp *= 0.5;
    }
    (h + 0.05 * noise).max(0.0)
}

/// The puff's texel at p: the normal of the height field, n ∝ (−∂h/∂x,
/// −∂h/∂y, 1) (central differences over `step`), and its opacity, rising
/// over the caps' first 0.15 of height and falling to 0 before the
/// square's inscribed circle ends (no visible quad edge).
pub fn puff_texel(p: Vec2, step: f32) -> (Vec3, f32) {
    let dx = puff_height(p + Vec2::X * step) - puff_height(p - Vec2::X * step);
    let dy = puff_height(p + Vec2::Y * step) - puff_height(p - Vec2::Y * step);
    let n = Vec3::new(-dx / (2.0 * step), -dy / (2.0 * step), 1.0).normalize();
    let smooth = |e0: f32, e1: f32, x: f32| {
        let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let a = smooth(0.0, 0.15, puff_height(p)) * (1.0 - smooth(0.85, 1.0, p.length()));
    (n, a)
}

/// Encodes a tangent-space normal and opacity as an RGBA8 texel.
fn encode(n: Vec3, a: f32) -> [u8; 4] {
    let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    [
        q(0.5 * n.x + 0.5),
        q(0.5 * n.y + 0.5),
        q(0.5 * n.z + 0.5),
        q(a),
    ]
}

/// The puff's mip-0 layer: [`SPRITE_SIZE`]² RGBA8, row 0 at the top
/// (p.y = +1), texel centres at p = (2 (i + ½) / size − 1, ...).
pub fn puff_layer() -> Vec<u8> {
    let size = SPRITE_SIZE as usize;
    let step = 1.0 / size as f32;
    let mut out = Vec::with_capacity(size * size * 4);
    for row in 0..size {
        for col in 0..size {
            let p = Vec2::new(
                2.0 * (col as f32 + 0.5) / size as f32 - 1.0,
                1.0 - 2.0 * (row as f32 + 0.5) / size as f32,
            );
            let (n, a) = puff_texel(p, step);
            out.extend(encode(n, a));
        }
    }
    out
}

/// The mip chain of a square RGBA8 layer (2 x 2 box filter), mip 0 first.
pub fn mip_chain(layer: &[u8], size: u32) -> Vec<Vec<u8>> {
    let mut mips = vec![layer.to_vec()];
    let mut s = size as usize;
    while s > 1 {
        let prev = mips.last().expect("mip 0");
        let h = s / 2;
        let mut next = vec![0u8; h * h * 4];
        for y in 0..h {
            for x in 0..h {
                for c in 0..4 {
                    let at = |dx: usize, dy: usize| {
                        u32::from(prev[((2 * y + dy) * s + 2 * x + dx) * 4 + c])
                    };
                    let sum = at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1);
                    next[(y * h + x) * 4 + c] = sum.div_ceil(4).min(255) as u8;
                }
            }
        }
        mips.push(next);
        s = h;
    }
    mips
}

/// GPU bytes of a sprite array of `layers` layers with their mip chains.
pub fn sprite_bytes(layers: u32) -> u64 {
    let per_layer: u64 = (0..=SPRITE_SIZE.ilog2())
        .map(|l| 4 * u64::from(SPRITE_SIZE >> l).pow(2))
        .sum();
    per_layer * u64::from(layers)
}

/// The sprite array on the GPU: layer 0 the puff, then `images` (mip-0
/// layers of [`SPRITE_SIZE`]²), each with its mip chain.
pub fn create_sprites(ctx: &crate::gpu::GpuContext, images: &[&[u8]]) -> wgpu::Texture {
    let puff = puff_layer();
    let layers: Vec<&[u8]> = std::iter::once(&puff[..])
        .chain(images.iter().copied())
        .collect();
    let mip_count = SPRITE_SIZE.ilog2() + 1;
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("particles.sprites"),
        size: wgpu::Extent3d {
            width: SPRITE_SIZE,
            height: SPRITE_SIZE,
            depth_or_array_layers: layers.len() as u32,
        },
        mip_level_count: mip_count,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: SPRITE_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (z, layer) in layers.iter().enumerate() {
        for (level, mip) in mip_chain(layer, SPRITE_SIZE).iter().enumerate() {
            let s = SPRITE_SIZE >> level;
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: level as u32,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: z as u32,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                mip,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * s),
                    rows_per_image: Some(s),
                },
                wgpu::Extent3d {
                    width: s,
                    height: s,
                    depth_or_array_layers: 1,
                },
            );
        }
    }
    texture
}

/// Each emitter's layer in the sprite array (−1: the disc, 0: the puff,
/// 1 + k: the k-th distinct image) and the distinct images in layer order.
pub fn sprite_layers(emitters: &[EmitterDesc]) -> (Vec<i32>, Vec<Arc<SpriteImage>>) {
    let mut images: Vec<Arc<SpriteImage>> = Vec::new();
    let layers = (emitters.iter())
        .map(|e| match &e.sprite {
            Sprite::Disc => -1,
            Sprite::Puff => 0,
            Sprite::Image(img) => {
                let k = (images.iter().position(|i| Arc::ptr_eq(i, img))).unwrap_or_else(|| {
                    images.push(img.clone());
                    images.len() - 1
                });
                1 + k as i32
            }
        })
        .collect();
    (layers, images)
}
