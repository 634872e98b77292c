//! Material textures of glTF scenes on the GPU: images uploaded once per
//! colour space they are used in (base colour and emissive sRGB, the rest
//! linear), full mip chains generated on the GPU (`mipmap.wgsl`), one
//! sampler per distinct glTF sampler, 1x1 defaults for absent slots, and a
//! uniform of factors per material (twin of `MaterialGpu` in
//! `shaders/gltf_material.wgsl`). CPU twin of the mip generation:
//! [`next_mip_reference`]. Images used only as normal textures get E3's
//! chain instead (`normal_mipmap.wgsl`, twin [`next_normal_mip_reference`]):
//! normalised averages with the normal variance in alpha.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::gpu::pipeline::target;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::math::brdf::{
    next_normal_variance_level, normal_variance_decode, normal_variance_encode,
};
use crate::scene::gltf::{
    AlphaMode, ImageData, NORMAL_SLOTS, PbrMaterial, PbrSet, SamplerDesc, TEXTURE_SLOTS, Wrap,
};

/// Twin of `MaterialGpu` in shaders/gltf_material.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MaterialGpu {
    /// Linear base colour factor and alpha.
    pub base_color: [f32; 4],
    /// Linear emissive (not drawn yet: the G-buffer has no emissive target).
    pub emissive: [f32; 4],
    /// x normal scale, y occlusion strength, z anisotropy strength, w anisotropy rotation (rad).
    pub params: [f32; 4],
    /// x alpha mode (0 opaque, 1 mask, 2 blend), y cut-off, z 1 when unlit,
    /// w 1 when the normal texture's alpha holds normal variance (E3).
    pub alpha: [f32; 4],
    /// KHR_materials_clearcoat: x factor, y roughness, z normal scale, w 1
    /// when the coat normal texture's alpha holds normal variance (E3).
    pub clearcoat: [f32; 4],
    /// KHR_materials_sheen: rgb colour (linear), a roughness.
    pub sheen: [f32; 4],
    /// KHR_materials_specular: rgb colour factor (linear), a specular factor.
    pub specular: [f32; 4],
    /// KHR_materials_transmission / _volume: x transmission factor, y
    /// thickness factor, z 1 / attenuation distance (0: none), w ior.
    pub transmission: [f32; 4],
    /// KHR_materials_volume: rgb attenuation colour (linear).
    pub attenuation: [f32; 4],
    /// KHR_texture_transform per slot (SLOTS order): the 2x3 matrix's two
    /// rows (xyz), identity where the slot has none; the first row's w is
    /// the slot's UV set (0: `Vertex::uv`, 1: `Vertex::uv1`).
    pub uv: [[f32; 4]; 2 * TEXTURE_SLOTS],
}

impl MaterialGpu {
    /// Packs a scene material's factors, alpha mode and texture transforms into the uniform layout.
    pub fn new(m: &PbrMaterial) -> Self {
        let (mode, cutoff) = match m.alpha_mode {
            AlphaMode::Opaque => (0.0, 0.0),
            AlphaMode::Mask(c) => (1.0, c),
            AlphaMode::Blend => (2.0, 0.0),
        };
        MaterialGpu {
            base_color: m.base_color.to_array(),
            emissive: m.emissive.extend(0.0).to_array(),
            params: [
                m.normal_scale,
                m.occlusion_strength,
                m.anisotropy_strength,
                m.anisotropy_rotation,
            ],
            alpha: [mode, cutoff, m.unlit as u32 as f32, 0.0],
            clearcoat: [
                m.clearcoat,
                m.clearcoat_roughness,
                m.clearcoat_normal_scale,
                0.0,
            ],
            sheen: m.sheen_color.extend(m.sheen_roughness).to_array(),
            specular: m.specular_color.extend(m.specular).to_array(),
            transmission: [
                m.transmission,
                m.thickness,
                1.0 / m.attenuation_distance,
                m.ior,
            ],
            attenuation: m.attenuation_color.extend(0.0).to_array(),
            uv: uv_rows(m),
        }
    }
}

/// The slots' texture transforms and UV sets as MaterialGpu::uv rows.
fn uv_rows(m: &PbrMaterial) -> [[f32; 4]; 2 * TEXTURE_SLOTS] {
    let slots = m.texture_refs();
    let mut rows = [[0.0; 4]; 2 * TEXTURE_SLOTS];
    for (k, t) in slots.iter().enumerate() {
        let r = t
            .and_then(|t| t.transform)
            .map_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], |x| x.rows());
        // The vertex slot holding the file's set (sets past two: slot 0, warned).
        let set = t.map_or(0.0, |t| m.uv_slot(t.tex_coord) as f32);
        rows[2 * k] = [r[0][0], r[0][1], r[0][2], set];
        rows[2 * k + 1] = [r[1][0], r[1][1], r[1][2], 0.0];
    }
    rows
}

/// The texture slots of a material, as named in shaders/gltf_material.wgsl
/// (`PbrMaterial::texture_refs` order).
pub const SLOTS: [&str; TEXTURE_SLOTS] = [
    "base_color",
    "metal_rough",
    "normal",
    "occlusion",
    "emissive",
    "anisotropy",
    "clearcoat",
    "clearcoat_roughness",
    "clearcoat_normal",
    "sheen_color",
    "sheen_roughness",
    "specular",
    "specular_color",
    "transmission",
    "thickness",
];

/// One material's GPU resources: (view, sampler) per slot and its uniform.
pub struct MaterialBinding {
    /// Uniform buffer holding the material's [`MaterialGpu`].
    pub uniform: wgpu::Buffer,
    /// Per slot: index into `MaterialTextures::views` and `samplers`.
    pub slots: [(usize, usize); TEXTURE_SLOTS],
    /// glTF `doubleSided`: drawn without back-face culling.
    pub double_sided: bool,
}

/// Every material texture of a scene on the GPU (deduplicated by image and
/// colour space), their samplers, and per-material bindings into them.
pub struct MaterialTextures {
    /// RGBA8 textures with full mip chains (sRGB or linear per use), defaults first.
    pub textures: Vec<wgpu::Texture>,
    /// One view per texture, same index.
    pub views: Vec<wgpu::TextureView>,
    /// Distinct samplers (wrap and filter modes), deduplicated.
    pub samplers: Vec<wgpu::Sampler>,
    /// One binding per scene material, in the scene's material order.
    pub materials: Vec<MaterialBinding>,
    /// Estimated bytes of all textures: 4 bytes a texel plus a third for the mips.
    pub bytes: u64,
}

fn address(w: Wrap) -> wgpu::AddressMode {
    match w {
        Wrap::Repeat => wgpu::AddressMode::Repeat,
        Wrap::Mirror => wgpu::AddressMode::MirrorRepeat,
        Wrap::Clamp => wgpu::AddressMode::ClampToEdge,
    }
}

fn filter(linear: bool) -> wgpu::FilterMode {
    if linear {
        wgpu::FilterMode::Linear
    } else {
        wgpu::FilterMode::Nearest
    }
}

/// A wgpu sampler for a glTF sampler; NEAREST / LINEAR min filters clamp to level 0.
pub fn sampler_descriptor(s: &SamplerDesc) -> wgpu::SamplerDescriptor<'static> {
    wgpu::SamplerDescriptor {
        label: Some("gltf.sampler"),
        address_mode_u: address(s.wrap_u),
        address_mode_v: address(s.wrap_v),
        mag_filter: filter(s.mag_linear),
        min_filter: filter(s.min_linear),
        mipmap_filter: if s.mip_linear {
            wgpu::MipmapFilterMode::Linear
        } else {
            wgpu::MipmapFilterMode::Nearest
        },
        lod_max_clamp: if s.mipmaps { 32.0 } else { 0.0 },
        ..Default::default()
    }
}

/// Mip levels of a full chain down to 1x1.
pub fn mip_count(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

/// One program's material bind groups ([`MaterialTextures::bind_groups`]),
/// made on first use for an uploaded scene and kept: frames draw with them
/// instead of creating one per material every frame (as the G-buffer and
/// forward passes once did).
#[derive(Default)]
pub struct MaterialGroups {
    cached: std::sync::Mutex<Option<(u64, std::sync::Arc<Vec<wgpu::BindGroup>>)>>,
    builds: std::sync::atomic::AtomicU32,
}

impl MaterialGroups {
    /// The bind groups of `program` for scene `scene_id`'s `materials`
    /// (`SceneGpu::id`): built once per scene.
    pub fn get(
        &self,
        scene_id: u64,
        materials: &MaterialTextures,
        program: &Program,
        device: &wgpu::Device,
    ) -> Result<std::sync::Arc<Vec<wgpu::BindGroup>>, GpuError> {
        let mut cached = (self.cached.lock()).map_err(|_| {
            GpuError::Other("material bind groups: a panic poisoned the cache".into())
        })?;
        if let Some((id, groups)) = cached.as_ref()
            && *id == scene_id
        {
            return Ok(groups.clone());
        }
        let groups = std::sync::Arc::new(materials.bind_groups(program, device)?);
        self.builds
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        *cached = Some((scene_id, groups.clone()));
        Ok(groups)
    }

    /// How many times the groups were built (tests: once per scene).
    pub fn builds(&self) -> u32 {
        self.builds.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl MaterialTextures {
    /// One bind group (group 1: `material` and the `<slot>_texture` /
    /// `<slot>_sampler` pairs) per material, for any program declaring that
    /// group (`textured.wgsl`, `forward.wgsl`).
    pub fn bind_groups(
        &self,
        program: &Program,
        device: &wgpu::Device,
    ) -> Result<Vec<wgpu::BindGroup>, GpuError> {
        let names: Vec<(String, String)> = SLOTS
            .iter()
            .map(|s| (format!("{s}_texture"), format!("{s}_sampler")))
            .collect();
        self.materials
            .iter()
            .map(|mat| {
                let mut entries = vec![("material", mat.uniform.as_entire_binding())];
                for ((tex, smp), (view, sampler)) in names.iter().zip(mat.slots) {
                    entries.push((tex, wgpu::BindingResource::TextureView(&self.views[view])));
                    entries.push((smp, wgpu::BindingResource::Sampler(&self.samplers[sampler])));
                }
                program.bind(device, 1, &entries)
            })
            .collect()
    }

    /// Uploads every image a material uses, generating mips (normal maps with
    /// E3 variance where baked), and makes each material's uniform and slot table.
    /// Absent slots get 1x1 defaults (white, flat normal, anisotropy along +t).
    pub fn upload(ctx: &GpuContext, pbr: &PbrSet) -> Result<Self, GpuError> {
        let mipmap = Program::new(ctx, "gpu_scene/mipmap.wgsl")?;
        let normal_mipmap = Program::new(ctx, "gpu_scene/normal_mipmap.wgsl")?;
        let (baked, _) = pbr.normal_variance_images();
        let mut out = MaterialTextures {
            textures: Vec::new(),
            views: Vec::new(),
            samplers: Vec::new(),
            materials: Vec::new(),
            bytes: 0,
        };
        let linear_sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        // Defaults for absent slots: white (base colour, metal-rough, occlusion,
        // emissive scaled by its factor), flat normal, anisotropy along +t at full strength.
        let one = |rgba: [u8; 4], name: &str| ImageData {
            name: name.into(),
            width: 1,
            height: 1,
            rgba8: rgba.to_vec(),
        };
        let defaults = [
            one([255, 255, 255, 255], "default.white"),
            // Flat, no variance (E3 alpha).
            one([128, 128, 255, 0], "default.normal"),
            one([255, 128, 255, 255], "default.anisotropy"),
        ];
        let mut uploaded: HashMap<(usize, bool), usize> = HashMap::new();
        let mut sampler_ids: HashMap<SamplerDesc, usize> = HashMap::new();
        let default_sampler = out.sampler(ctx, &mut sampler_ids, &SamplerDesc::default());
        let plain = Mips::Plain(&mipmap, &linear_sampler);
        let white_srgb = out.add_image(ctx, plain, &defaults[0], true)?;
        let white = out.add_image(ctx, plain, &defaults[0], false)?;
        let flat = out.add_image(
            ctx,
            Mips::Normal(&normal_mipmap, &linear_sampler),
            &defaults[1],
            false,
        )?;
        let along_t = out.add_image(ctx, plain, &defaults[2], false)?;
        for m in &pbr.materials {
            // Per slot: sRGB or linear, and the default where it is absent.
            let (srgb, fallback) = (
                [
                    true, false, false, false, true, false, false, false, false, true, false,
                    false, true, false, false,
                ],
                [
                    white_srgb, white, flat, white, white_srgb, along_t, white, white, flat,
                    white_srgb, white, white, white_srgb, white, white,
                ],
            );
            let refs = (m.texture_refs().into_iter().zip(srgb)).zip(fallback);
            let mut slots = [(0, 0); TEXTURE_SLOTS];
            // E3: whether the normal / coat normal slot's alpha is variance.
            let mut variance = [false; 2];
            for (k, (slot, ((r, srgb), fallback))) in slots.iter_mut().zip(refs).enumerate() {
                *slot = match r.and_then(|r| pbr.textures.get(r.texture)) {
                    Some(t) => {
                        let image = pbr.images.get(t.image).ok_or_else(|| {
                            GpuError::Other(format!(
                                "texture names image {} of {}",
                                t.image,
                                pbr.images.len()
                            ))
                        })?;
                        let bake = !srgb && baked.get(t.image).copied().unwrap_or(false);
                        if let Some(n) = NORMAL_SLOTS.iter().position(|&n| n == k) {
                            variance[n] = bake;
                        }
                        let view = match uploaded.get(&(t.image, srgb)) {
                            Some(&v) => v,
                            None => {
                                let mips = if bake {
                                    Mips::Normal(&normal_mipmap, &linear_sampler)
                                } else {
                                    plain
                                };
                                let v = out.add_image(ctx, mips, image, srgb)?;
                                uploaded.insert((t.image, srgb), v);
                                v
                            }
                        };
                        (view, out.sampler(ctx, &mut sampler_ids, &t.sampler))
                    }
                    None => (fallback, default_sampler),
                };
            }
            let mut gpu = MaterialGpu::new(m);
            gpu.alpha[3] = f32::from(u8::from(variance[0]));
            gpu.clearcoat[3] = f32::from(u8::from(variance[1]));
            let uniform = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("gltf.material"),
                    contents: bytemuck::bytes_of(&gpu),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
            out.materials.push(MaterialBinding {
                uniform,
                slots,
                double_sided: m.double_sided,
            });
        }
        ctx.check("gltf textures")?;
        Ok(out)
    }

    fn sampler(
        &mut self,
        ctx: &GpuContext,
        ids: &mut HashMap<SamplerDesc, usize>,
        s: &SamplerDesc,
    ) -> usize {
        *ids.entry(*s).or_insert_with(|| {
            self.samplers
                .push(ctx.device.create_sampler(&sampler_descriptor(s)));
            self.samplers.len() - 1
        })
    }

    /// Uploads level 0 and renders the rest of the chain; returns the view index.
    fn add_image(
        &mut self,
        ctx: &GpuContext,
        mips: Mips,
        image: &ImageData,
        srgb: bool,
    ) -> Result<usize, GpuError> {
        let format = if srgb {
            wgpu::TextureFormat::Rgba8UnormSrgb
        } else {
            wgpu::TextureFormat::Rgba8Unorm
        };
        let (w, h) = (image.width, image.height);
        if image.rgba8.len() != (w * h * 4) as usize {
            return Err(GpuError::Other(format!(
                "image \"{}\": {} bytes for {w}x{h}",
                image.name,
                image.rgba8.len()
            )));
        }
        let levels = mip_count(w, h);
        let size = wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(&image.name),
            size,
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            // COPY_SRC: the mip twin test reads levels back.
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        // E3: a normal map's level 0 has no variance (glTF ignores its alpha).
        let zero_alpha;
        let level0 = match mips {
            Mips::Normal(..) => {
                let mut t = image.rgba8.clone();
                t.chunks_exact_mut(4).for_each(|p| p[3] = 0);
                zero_alpha = t;
                &zero_alpha
            }
            Mips::Plain(..) => &image.rgba8,
        };
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            level0,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 4),
                rows_per_image: Some(h),
            },
            size,
        );
        if levels > 1 {
            let (program, label) = match mips {
                Mips::Plain(p, _) => (p, "renderer.mipmap"),
                Mips::Normal(p, _) => (p, "renderer.normal_mipmap"),
            };
            let targets = [target(format)];
            let mut spec = RenderSpec::fullscreen(label, &targets);
            let pipeline = program.render_pipeline(ctx, &spec)?;
            // E3: level 1 takes the variance of level 0's bilinear field.
            let first = match mips {
                Mips::Plain(..) => pipeline.clone(),
                Mips::Normal(..) => {
                    spec.constants = &[("FROM_LEVEL0", 1.0)];
                    program.render_pipeline(ctx, &spec)?
                }
            };
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            for level in 1..levels {
                let view = |l: u32| {
                    texture.create_view(&wgpu::TextureViewDescriptor {
                        base_mip_level: l,
                        mip_level_count: Some(1),
                        ..Default::default()
                    })
                };
                let (src, dst) = (view(level - 1), view(level));
                let source = wgpu::BindingResource::TextureView(&src);
                let bind = match mips {
                    Mips::Plain(p, sampler) => p.bind(
                        &ctx.device,
                        0,
                        &[
                            ("source", source),
                            ("source_sampler", wgpu::BindingResource::Sampler(sampler)),
                        ],
                    )?,
                    Mips::Normal(p, sampler) => p.bind(
                        &ctx.device,
                        0,
                        &[
                            ("source", source),
                            ("source_sampler", wgpu::BindingResource::Sampler(sampler)),
                        ],
                    )?,
                };
                let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(label),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &dst,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                rp.set_pipeline(if level == 1 { &first } else { &pipeline });
                rp.set_bind_group(0, &bind, &[]);
                rp.draw(0..3, 0..1);
            }
            ctx.queue.submit([encoder.finish()]);
        }
        self.bytes += (w as u64 * h as u64 * 4 * 4) / 3;
        self.views.push(texture.create_view(&Default::default()));
        self.textures.push(texture);
        Ok(self.views.len() - 1)
    }
}

/// How an image's mip chain is made.
#[derive(Clone, Copy)]
enum Mips<'a> {
    /// 2x2 box (`mipmap.wgsl`, one bilinear tap with this sampler).
    Plain(&'a Program, &'a wgpu::Sampler),
    /// E3 normal map: normalised mean, normal variance in alpha (`normal_mipmap.wgsl`).
    Normal(&'a Program, &'a wgpu::Sampler),
}

fn srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn srgb_encode(c: f32) -> f32 {
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// CPU twin of `mipmap.wgsl`: the level after a `width` x `height` RGBA8
/// level. Texel (x, y) is the bilinear tap at the source's texel coordinate
/// (2x + 1, 2y + 1), i.e. the mean of texels 2x, 2x + 1 (clamped to the
/// edge) by 2y, 2y + 1; an odd last row / column is dropped, as the shader
/// does. `srgb`: colour is decoded before the mean and encoded after it
/// (alpha stays linear), like an `Rgba8UnormSrgb` view. Rounded to 8 bits.
pub fn next_mip_reference(
    width: u32,
    height: u32,
    rgba8: &[u8],
    srgb: bool,
) -> (u32, u32, Vec<u8>) {
    let (w, h) = ((width / 2).max(1), (height / 2).max(1));
    let texel = |x: u32, y: u32, c: usize| {
        let v =
            rgba8[((y.min(height - 1) * width + x.min(width - 1)) * 4) as usize + c] as f32 / 255.0;
        if srgb && c < 3 { srgb_decode(v) } else { v }
    };
    let mut out = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            for c in 0..4 {
                let (x0, y0) = (2 * x, 2 * y);
                let mean = 0.25
                    * (texel(x0, y0, c)
                        + texel(x0 + 1, y0, c)
                        + texel(x0, y0 + 1, c)
                        + texel(x0 + 1, y0 + 1, c));
                let v = if srgb && c < 3 {
                    srgb_encode(mean)
                } else {
                    mean
                };
                out.push((v.clamp(0.0, 1.0) * 255.0).round() as u8);
            }
        }
    }
    (w, h, out)
}

/// CPU twin of `normal_mipmap.wgsl` (E3): the level after a `width` x
/// `height` normal-map level whose alpha holds encoded normal variance
/// (level 0: alpha 0). Texel (x, y) reads parents 2x, 2x + 1 by 2y, 2y + 1
/// (clamped to the edge), normalises each RGB to n_i, and writes RGB =
/// encode(normalize(m)) with m = mean(n_i) and alpha = encode(sigma^2),
/// sigma^2 = mean(sigma_i^2) plus (1 - |m|) / |m|. `from_level0` (the source
/// is level 0): sigma^2 is the spread (1 - |m'|) / |m'| of the bilinear
/// field instead, m' the mean of its unit normals over the footprint by
/// two-point Gauss-Legendre on the field's linear pieces (6 x 6 nodes).
/// Computed in f32, rounded to 8 bits.
pub fn next_normal_mip_reference(
    width: u32,
    height: u32,
    rgba8: &[u8],
    from_level0: bool,
) -> (u32, u32, Vec<u8>) {
    let texel = |x: i32, y: i32| {
        let (x, y) = (x.clamp(0, width as i32 - 1), y.clamp(0, height as i32 - 1));
        let i = ((y as u32 * width + x as u32) * 4) as usize;
        let c = |k: usize| rgba8[i + k] as f32 / 255.0;
        (
            glam::Vec3::new(c(0), c(1), c(2)),
            normal_variance_decode(c(3)),
        )
    };
    let unorm = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let level = next_normal_variance_level(width, height, texel, from_level0);
    let out = (level.iter())
        .flat_map(|&(n, variance)| {
            let rgb = n * 0.5 + 0.5;
            [
                unorm(rgb.x),
                unorm(rgb.y),
                unorm(rgb.z),
                unorm(normal_variance_encode(variance)),
            ]
        })
        .collect();
    ((width / 2).max(1), (height / 2).max(1), out)
}
