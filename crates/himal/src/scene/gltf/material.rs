//! glTF materials, textures, samplers and images -> [`PbrSet`] entries.
//!
//! Metallic-roughness maps onto the himal material (TECHNIQUES M1) as the
//! inverse of its glossiness mapping: `glossiness = 1 - roughness` (himal's
//! perceptual roughness is `1 - glossiness`, alpha = roughness²). glTF's
//! dielectric F0 is 0.04 (ior 1.5); himal's `reflectance` *is* F0, so it is
//! 0.04 (Filament's reflectance 0.5 ↔ F0 = 0.16·0.5² = 0.04). See docs/gltf.md.

use std::path::Path;

use glam::{Vec3, Vec4};

use super::{GltfContext, MAX_TEXTURE_SIZE};
use crate::scene::SceneError;

/// Texture slots of a material (`PbrMaterial::texture_refs`).
pub const TEXTURE_SLOTS: usize = 15;

/// The normal and clearcoat normal slots in `PbrMaterial::texture_refs`
/// order: images used only there carry normal variance in their mips (E3).
pub const NORMAL_SLOTS: [usize; 2] = [2, 8];

/// Reflectance (F0) of glTF dielectrics: ior 1.5.
pub const GLTF_DIELECTRIC_F0: f32 = 0.04;

/// How a material's alpha is used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored; the surface is fully opaque.
    Opaque,
    /// Alpha test: fragments with alpha < cutoff are discarded.
    Mask(f32),
    /// Blended over the opaque scene by `forward.blend`; as a shadow caster
    /// a mask at [`AlphaMode::BLEND_CASTER_CUTOFF`].
    Blend,
}

impl AlphaMode {
    /// The cut-off BLEND surfaces cast shadows with (docs/gltf.md "Alpha in
    /// shadows"): a pane mostly see-through casts nothing, a mostly opaque
    /// one casts as if opaque.
    pub const BLEND_CASTER_CUTOFF: f32 = 0.5;

    /// Whether a fragment of coverage `alpha` (base colour factor × texture
    /// alpha) is cut away: MASK below its cut-off; as a shadow caster
    /// (`caster`) BLEND below [`Self::BLEND_CASTER_CUTOFF`] too. CPU twin of
    /// `gltf_cut_out` (`shaders/gltf_material.wgsl`).
    pub fn cuts(self, alpha: f32, caster: bool) -> bool {
        match self {
            AlphaMode::Opaque => false,
            AlphaMode::Mask(cutoff) => alpha < cutoff,
            AlphaMode::Blend => caster && alpha < Self::BLEND_CASTER_CUTOFF,
        }
    }
}

/// A texture used by a material slot and the UV set it reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`super::PbrSet::textures`].
    pub texture: usize,
    /// The file's UV set read, `TEXCOORD_<tex_coord>` (after any
    /// `KHR_texture_transform` override); [`PbrMaterial::uv_slot`] says
    /// which of the vertex's two UV slots holds it.
    pub tex_coord: u32,
    /// `KHR_texture_transform` of this use of the texture.
    pub transform: Option<UvTransform>,
}

/// `KHR_texture_transform`: uv' = T(offset) R(rotation) S(scale) (u, v, 1),
/// R = [cos sin; -sin cos] as the extension specifies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Translation in UV units, applied last.
    pub offset: glam::Vec2,
    /// Radians.
    pub rotation: f32,
    /// Scale per UV axis, applied first.
    pub scale: glam::Vec2,
}

impl UvTransform {
    /// The two rows of the 2x3 matrix.
    pub fn rows(&self) -> [[f32; 3]; 2] {
        let (s, c) = self.rotation.sin_cos();
        let (sx, sy) = (self.scale.x, self.scale.y);
        [
            [c * sx, s * sy, self.offset.x],
            [-s * sx, c * sy, self.offset.y],
        ]
    }

    /// Transforms a UV coordinate by [`Self::rows`].
    pub fn apply(&self, uv: glam::Vec2) -> glam::Vec2 {
        let [r0, r1] = self.rows();
        glam::Vec2::new(
            r0[0] * uv.x + r0[1] * uv.y + r0[2],
            r1[0] * uv.x + r1[1] * uv.y + r1[2],
        )
    }
}

const TEXTURE_TRANSFORM: &str = "KHR_texture_transform";

/// A texture info's `KHR_texture_transform` object (and the UV set it
/// overrides to), checked finite.
fn uv_transform(
    cx: &GltfContext,
    transform: Option<&gltf::json::Value>,
    tex_coord: u32,
) -> Result<(Option<UvTransform>, u32), SceneError> {
    let Some(t) = transform else {
        return Ok((None, tex_coord));
    };
    let pair = |key: &str, default: [f32; 2]| -> Result<glam::Vec2, SceneError> {
        let Some(v) = t.get(key) else {
            return Ok(glam::Vec2::from(default));
        };
        let a = v.as_array().filter(|a| a.len() == 2);
        let xy: Option<Vec<f32>> = a.map(|a| {
            a.iter()
                .filter_map(|c| c.as_f64())
                .map(|c| c as f32)
                .collect()
        });
        match xy {
            Some(xy) if xy.len() == 2 && xy.iter().all(|c| c.is_finite()) => {
                Ok(glam::Vec2::new(xy[0], xy[1]))
            }
            _ => Err(cx.invalid(format!(
                "KHR_texture_transform {key} {v}: expected two finite numbers"
            ))),
        }
    };
    let rotation = match t.get("rotation") {
        None => 0.0,
        Some(v) => v
            .as_f64()
            .map(|r| r as f32)
            .filter(|r| r.is_finite())
            .ok_or_else(|| {
                cx.invalid(format!(
                    "KHR_texture_transform rotation {v}: not a finite number"
                ))
            })?,
    };
    let tex_coord = t
        .get("texCoord")
        .and_then(|v| v.as_u64())
        .map_or(tex_coord, |k| k as u32);
    Ok((
        Some(UvTransform {
            offset: pair("offset", [0.0, 0.0])?,
            rotation,
            scale: pair("scale", [1.0, 1.0])?,
        }),
        tex_coord,
    ))
}

/// glTF texture wrap modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// Tile the texture (glTF `REPEAT`).
    Repeat,
    /// Tile with every other copy mirrored (glTF `MIRRORED_REPEAT`).
    Mirror,
    /// Clamp to the edge texels (glTF `CLAMP_TO_EDGE`).
    Clamp,
}

/// A sampler: wrap per axis, magnification / minification / mip filters (linear = true).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SamplerDesc {
    /// Wrap mode along u.
    pub wrap_u: Wrap,
    /// Wrap mode along v.
    pub wrap_v: Wrap,
    /// Bilinear magnification (false: nearest).
    pub mag_linear: bool,
    /// Bilinear minification within a level (false: nearest).
    pub min_linear: bool,
    /// Blend between mip levels (false: nearest level).
    pub mip_linear: bool,
    /// False for NEAREST / LINEAR min filters: only level 0 is sampled.
    pub mipmaps: bool,
}

impl Default for SamplerDesc {
    /// glTF leaves filters to the implementation: trilinear, repeat.
    fn default() -> Self {
        SamplerDesc {
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            mag_linear: true,
            min_linear: true,
            mip_linear: true,
            mipmaps: true,
        }
    }
}

/// A texture: an image and how to sample it.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSlot {
    /// Index into [`super::PbrSet::images`].
    pub image: usize,
    /// How the image is sampled.
    pub sampler: SamplerDesc,
}

/// A decoded image, 8-bit RGBA, rows top to bottom (glTF uv (0,0) is the top-left).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageData {
    /// The glTF image's name, else a label such as `image 3 "wood.png"`.
    pub name: String,
    /// Width in pixels (1..=the texture size limit).
    pub width: u32,
    /// Height in pixels (1..=the texture size limit).
    pub height: u32,
    /// `width * height * 4` bytes, RGBA8, as stored (sRGB or linear depends on the slot using it).
    pub rgba8: Vec<u8>,
}

/// A glTF metallic-roughness material with its extensions, factors linear.
#[derive(Clone, Debug, PartialEq)]
pub struct PbrMaterial {
    /// The glTF material's name, else `material<index>`.
    pub name: String,
    /// Linear base colour and alpha.
    pub base_color: Vec4,
    /// Metalness factor in \[0,1\] (multiplies the texture's B channel).
    pub metallic: f32,
    /// Perceptual roughness; himal glossiness = 1 - roughness.
    pub roughness: f32,
    /// Linear emitted colour times KHR_materials_emissive_strength.
    pub emissive: Vec3,
    /// Scale of the normal map's x and y (glTF `normalTexture.scale`).
    pub normal_scale: f32,
    /// How much the occlusion texture darkens, in \[0,1\] (glTF `occlusionTexture.strength`).
    pub occlusion_strength: f32,
    /// How alpha is used (glTF `alphaMode` and `alphaCutoff`).
    pub alpha_mode: AlphaMode,
    /// glTF `doubleSided`: drawn without back-face culling.
    pub double_sided: bool,
    /// KHR_materials_anisotropy `anisotropyStrength` in [0, 1].
    pub anisotropy_strength: f32,
    /// KHR_materials_anisotropy `anisotropyRotation` (radians, counter-clockwise from +u toward +v... in the tangent frame).
    pub anisotropy_rotation: f32,
    /// sRGB base colour and linear alpha, multiplied by `base_color`.
    pub base_color_texture: Option<TextureRef>,
    /// G roughness, B metallic.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normal map (RGB = xyz * 0.5 + 0.5).
    pub normal_texture: Option<TextureRef>,
    /// R occlusion.
    pub occlusion_texture: Option<TextureRef>,
    /// sRGB emissive colour, multiplied by `emissive`.
    pub emissive_texture: Option<TextureRef>,
    /// RG direction in [-1, 1] (tangent, bitangent), B strength.
    pub anisotropy_texture: Option<TextureRef>,
    /// KHR_materials_clearcoat `clearcoatFactor` in [0, 1] (0: no coat).
    pub clearcoat: f32,
    /// The coat's perceptual roughness.
    pub clearcoat_roughness: f32,
    /// The coat normal texture's `scale`.
    pub clearcoat_normal_scale: f32,
    /// R × `clearcoat`.
    pub clearcoat_texture: Option<TextureRef>,
    /// G × `clearcoat_roughness`.
    pub clearcoat_roughness_texture: Option<TextureRef>,
    /// The coat's own normal map (absent: the geometric normal, as the
    /// extension says, not the base's normal map).
    pub clearcoat_normal_texture: Option<TextureRef>,
    /// KHR_materials_sheen `sheenColorFactor`, linear (0: no sheen).
    pub sheen_color: Vec3,
    /// The sheen's perceptual roughness.
    pub sheen_roughness: f32,
    /// RGB (sRGB) × `sheen_color`.
    pub sheen_color_texture: Option<TextureRef>,
    /// A × `sheen_roughness`.
    pub sheen_roughness_texture: Option<TextureRef>,
    /// KHR_materials_unlit: the base colour is shown as it is, not lit
    /// (`forward.unlit`); the other properties are ignored.
    pub unlit: bool,
    /// KHR_materials_ior: the dielectric's index of refraction (1.5).
    pub ior: f32,
    /// KHR_materials_specular `specularFactor`: scales the dielectric's F0
    /// and sets its F90 (1: glTF's default dielectric).
    pub specular: f32,
    /// `specularColorFactor`, linear: tints the dielectric's F0 (not F90);
    /// may exceed 1 (F0 is clamped to 1 after the ior's F0 scales it).
    pub specular_color: Vec3,
    /// A × `specular`.
    pub specular_texture: Option<TextureRef>,
    /// RGB (sRGB) × `specular_color`.
    pub specular_color_texture: Option<TextureRef>,
    /// KHR_materials_transmission `transmissionFactor` in [0, 1] (0: opaque
    /// dielectric): the share of the diffuse base that is transmitted
    /// instead (`forward.transmission`, passes/forward).
    pub transmission: f32,
    /// R × `transmission`.
    pub transmission_texture: Option<TextureRef>,
    /// KHR_materials_volume `thicknessFactor`, in the mesh's units (0:
    /// thin-walled, no refraction offset or attenuation).
    pub thickness: f32,
    /// G × `thickness`.
    pub thickness_texture: Option<TextureRef>,
    /// `attenuationDistance` (m, world units): the distance at which light
    /// keeps `attenuation_color`; infinite: no absorption.
    pub attenuation_distance: f32,
    /// `attenuationColor`, linear.
    pub attenuation_color: Vec3,
}

impl Default for PbrMaterial {
    /// glTF's default material: white, fully metallic and rough.
    fn default() -> Self {
        PbrMaterial {
            name: "default".into(),
            base_color: Vec4::ONE,
            metallic: 1.0,
            roughness: 1.0,
            emissive: Vec3::ZERO,
            normal_scale: 1.0,
            occlusion_strength: 1.0,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            anisotropy_strength: 0.0,
            anisotropy_rotation: 0.0,
            base_color_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            occlusion_texture: None,
            emissive_texture: None,
            anisotropy_texture: None,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            clearcoat_normal_scale: 1.0,
            clearcoat_texture: None,
            clearcoat_roughness_texture: None,
            clearcoat_normal_texture: None,
            sheen_color: Vec3::ZERO,
            sheen_roughness: 0.0,
            sheen_color_texture: None,
            sheen_roughness_texture: None,
            unlit: false,
            ior: 1.5,
            specular: 1.0,
            specular_color: Vec3::ONE,
            specular_texture: None,
            specular_color_texture: None,
            transmission: 0.0,
            transmission_texture: None,
            thickness: 0.0,
            thickness_texture: None,
            attenuation_distance: f32::INFINITY,
            attenuation_color: Vec3::ONE,
        }
    }
}

impl PbrMaterial {
    /// himal glossiness of this material's roughness factor.
    pub fn glossiness(&self) -> f32 {
        glossiness_from_roughness(self.roughness)
    }

    /// `Vertex::color`: linear base colour and ao 1 (occlusion comes from the texture).
    pub fn vertex_color(&self) -> [f32; 4] {
        [self.base_color.x, self.base_color.y, self.base_color.z, 1.0]
    }

    /// Dielectric reflectance F0 = ((ior − 1) / (ior + 1))² (0.04 at the
    /// default 1.5): himal's M1 reflectance *is* F0, so this is exact.
    pub fn reflectance(&self) -> f32 {
        if self.ior == 1.5 {
            // The same bits as before the extension for every default material.
            return GLTF_DIELECTRIC_F0;
        }
        let n = self.ior.max(1.0);
        ((n - 1.0) / (n + 1.0)).powi(2)
    }

    /// `Vertex::surface`: glossiness, reflectance, metallic, anisotropy strength.
    pub fn vertex_surface(&self) -> [f32; 4] {
        [
            self.glossiness(),
            self.reflectance(),
            self.metallic,
            self.anisotropy_strength,
        ]
    }

    /// The texture slots in `gpu_scene::textures::SLOTS` order.
    pub fn texture_refs(&self) -> [Option<TextureRef>; TEXTURE_SLOTS] {
        [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.normal_texture,
            self.occlusion_texture,
            self.emissive_texture,
            self.anisotropy_texture,
            self.clearcoat_texture,
            self.clearcoat_roughness_texture,
            self.clearcoat_normal_texture,
            self.sheen_color_texture,
            self.sheen_roughness_texture,
            self.specular_texture,
            self.specular_color_texture,
            self.transmission_texture,
            self.thickness_texture,
        ]
    }

    /// The slots' references, mutable, in the same order.
    pub fn texture_refs_mut(&mut self) -> [&mut Option<TextureRef>; TEXTURE_SLOTS] {
        [
            &mut self.base_color_texture,
            &mut self.metallic_roughness_texture,
            &mut self.normal_texture,
            &mut self.occlusion_texture,
            &mut self.emissive_texture,
            &mut self.anisotropy_texture,
            &mut self.clearcoat_texture,
            &mut self.clearcoat_roughness_texture,
            &mut self.clearcoat_normal_texture,
            &mut self.sheen_color_texture,
            &mut self.sheen_roughness_texture,
            &mut self.specular_texture,
            &mut self.specular_color_texture,
            &mut self.transmission_texture,
            &mut self.thickness_texture,
        ]
    }

    /// Whether the material has a clearcoat or sheen layer over its base.
    pub fn coated(&self) -> bool {
        !self.unlit && (self.clearcoat > 0.0 || self.sheen_color.max_element() > 0.0)
    }

    /// Whether KHR_materials_specular makes the dielectric's Fresnel other
    /// than the G-buffer's grey F0 with F90 = 1 can hold (a coloured F0 or
    /// F90 < 1; docs/gltf.md "Specular").
    pub fn specular_differs(&self) -> bool {
        !self.unlit
            && (self.metallic < 1.0 || self.metallic_roughness_texture.is_some())
            && (self.specular != 1.0
                || self.specular_color != Vec3::ONE
                || self.specular_texture.is_some()
                || self.specular_color_texture.is_some())
    }

    /// Whether `forward.layers` (passes/forward) draws over this material's
    /// deferred base: a coat or sheen, or the specular the G-buffer cannot hold.
    /// Transmissive materials have no deferred base.
    pub fn layered(&self) -> bool {
        !self.transmits() && (self.coated() || self.specular_differs())
    }

    /// Whether KHR_materials_transmission lets light through: such surfaces
    /// are not in the G-buffer but drawn by `forward.transmission` over the
    /// opaque scene they refract (passes/forward).
    pub fn transmits(&self) -> bool {
        !self.unlit && self.transmission > 0.0
    }

    /// The dielectric's F0 and F90 of KHR_materials_specular from the
    /// factors and the textures' samples (`specular_a`: the specular
    /// texture's A, `color_rgb`: the colour texture's linear RGB):
    /// (min(F0(ior) × colour, 1) × specular, specular). Twin of
    /// `gltf_dielectric_fresnel` in shaders/gltf_material.wgsl.
    pub fn dielectric_fresnel(&self, specular_a: f32, color_rgb: Vec3) -> (Vec3, f32) {
        let s = self.specular * specular_a;
        let f0 = (self.reflectance() * self.specular_color * color_rgb).min(Vec3::ONE) * s;
        (f0, s)
    }

    /// Whether the material emits light (`forward.emissive`; unlit ones do
    /// not, transmissive ones add their emission in `forward.transmission`).
    pub fn emits(&self) -> bool {
        !self.unlit && self.emissive.max_element() > 0.0
    }

    /// Number of texture slots in use.
    pub fn texture_count(&self) -> usize {
        self.texture_refs().iter().flatten().count()
    }

    /// Whether a texture slot reads UV set `set`.
    pub fn reads_uv_set(&self, set: u32) -> bool {
        (self.texture_refs().iter().flatten()).any(|t| t.tex_coord == set)
    }

    /// The file's UV sets the vertex's two slots (`Vertex::uv`, `uv1`)
    /// carry for this material: TEXCOORD_0 and _1 while it reads no later
    /// set, else the two lowest sets it reads (a third set and beyond read
    /// the first slot, warned at load).
    pub fn uv_sets(&self) -> [u32; 2] {
        let mut sets: Vec<u32> = (self.texture_refs().iter().flatten())
            .map(|t| t.tex_coord)
            .collect();
        sets.sort_unstable();
        sets.dedup();
        match sets.as_slice() {
            s if s.iter().all(|&k| k <= 1) => [0, 1],
            [a] => [*a, *a],
            [a, b, ..] => [*a, *b],
            [] => [0, 1],
        }
    }

    /// The vertex UV slot (0: `uv`, 1: `uv1`) that holds UV set `set`.
    pub fn uv_slot(&self, set: u32) -> u32 {
        let [s0, s1] = self.uv_sets();
        u32::from(set != s0 && set == s1)
    }

    /// The UV sets the material reads that neither vertex slot holds.
    pub fn uv_sets_past_slots(&self) -> Vec<u32> {
        let slots = self.uv_sets();
        let mut past: Vec<u32> = (self.texture_refs().iter().flatten())
            .map(|t| t.tex_coord)
            .filter(|k| !slots.contains(k))
            .collect();
        past.sort_unstable();
        past.dedup();
        past
    }
}

/// The inverse of M1's `perceptual_roughness_from_glossiness` (r = 1 - g).
pub fn glossiness_from_roughness(roughness: f32) -> f32 {
    1.0 - roughness.clamp(0.0, 1.0)
}

/// himal anisotropy for a KHR_materials_anisotropy strength at GGX alpha
/// `alpha`: the extension stretches alpha_t to mix(alpha, 1, s²); himal
/// divides alpha by aspect = sqrt(1 - 0.9 a) along t and multiplies along b,
/// so equal ratios alpha_t / alpha_b give 1 / aspect² = mix(alpha, 1, s²) / alpha.
pub fn anisotropy_from_khr(strength: f32, alpha: f32) -> f32 {
    let alpha = alpha.max(0.002);
    let s = strength.clamp(0.0, 1.0);
    let alpha_t = alpha + (1.0 - alpha) * s * s;
    ((1.0 - alpha / alpha_t) / 0.9).clamp(0.0, 1.0)
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn wrap(mode: gltf::texture::WrappingMode) -> Wrap {
    use gltf::texture::WrappingMode as W;
    match mode {
        W::Repeat => Wrap::Repeat,
        W::MirroredRepeat => Wrap::Mirror,
        W::ClampToEdge => Wrap::Clamp,
    }
}

pub(super) fn sampler(s: &gltf::texture::Sampler) -> SamplerDesc {
    use gltf::texture::{MagFilter, MinFilter};
    let mut out = SamplerDesc {
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
        ..SamplerDesc::default()
    };
    if let Some(m) = s.mag_filter() {
        out.mag_linear = m == MagFilter::Linear;
    }
    if let Some(m) = s.min_filter() {
        let (min, mip, mipmaps) = match m {
            MinFilter::Nearest => (false, false, false),
            MinFilter::Linear => (true, false, false),
            MinFilter::NearestMipmapNearest => (false, false, true),
            MinFilter::LinearMipmapNearest => (true, false, true),
            MinFilter::NearestMipmapLinear => (false, true, true),
            MinFilter::LinearMipmapLinear => (true, true, true),
        };
        out.min_linear = min;
        out.mip_linear = mip;
        out.mipmaps = mipmaps;
    }
    out
}

fn texture_ref(cx: &GltfContext, info: &gltf::texture::Info) -> Result<TextureRef, SceneError> {
    let (transform, tex_coord) = uv_transform(
        cx,
        info.extensions().and_then(|e| e.get(TEXTURE_TRANSFORM)),
        info.tex_coord(),
    )?;
    Ok(TextureRef {
        texture: info.texture().index(),
        tex_coord,
        transform,
    })
}

/// `{ "index": i, "texCoord": k }` of extension `ext`, checked against the texture count.
fn json_texture_ref(
    cx: &GltfContext,
    ext: &str,
    v: Option<&gltf::json::Value>,
    textures: usize,
) -> Result<Option<TextureRef>, SceneError> {
    let Some(v) = v else { return Ok(None) };
    let index = v.get("index").and_then(|i| i.as_u64());
    match index {
        Some(i) if (i as usize) < textures => {
            let tex_coord = v.get("texCoord").and_then(|t| t.as_u64()).unwrap_or(0) as u32;
            let ext = v.get("extensions").and_then(|e| e.get(TEXTURE_TRANSFORM));
            let (transform, tex_coord) = uv_transform(cx, ext, tex_coord)?;
            Ok(Some(TextureRef {
                texture: i as usize,
                tex_coord,
                transform,
            }))
        }
        _ => Err(cx.invalid(format!(
            "{ext} texture {v} names no texture (there are {textures})"
        ))),
    }
}

/// `key` of extension object `v` as three finite numbers (`default` when absent).
fn json_vec3(
    cx: &GltfContext,
    ext: &str,
    v: &gltf::json::Value,
    key: &str,
    default: Vec3,
) -> Result<Vec3, SceneError> {
    let Some(x) = v.get(key) else {
        return Ok(default);
    };
    let c: Vec<f32> = (x.as_array().into_iter().flatten())
        .filter_map(|x| x.as_f64().map(|x| x as f32))
        .collect();
    if c.len() != 3 || !c.iter().all(|x| x.is_finite()) {
        return Err(cx.invalid(format!("{ext} {key} {x}: expected three finite numbers")));
    }
    Ok(Vec3::from_slice(&c))
}

/// Finite number from extension `ext`'s JSON, `default` when absent.
fn json_f32(
    cx: &GltfContext,
    ext: &str,
    v: &gltf::json::Value,
    key: &str,
    default: f32,
) -> Result<f32, SceneError> {
    match v.get(key) {
        None => Ok(default),
        Some(x) => match x.as_f64() {
            Some(f) if f.is_finite() => Ok(f as f32),
            _ => Err(cx.invalid(format!("{ext} {key} = {x} is not a number"))),
        },
    }
}

fn finite(cx: &GltfContext, what: &str, values: &[f32]) -> Result<(), SceneError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(cx.invalid(format!("{what} {values:?} must be finite")))
    }
}

pub(super) fn material(
    cx: &GltfContext,
    m: &gltf::Material,
    textures: usize,
) -> Result<PbrMaterial, SceneError> {
    let pbr = m.pbr_metallic_roughness();
    let name = m.name().map_or_else(
        || format!("material{}", m.index().unwrap_or(0)),
        str::to_string,
    );
    let base = pbr.base_color_factor();
    let emissive = m.emissive_factor();
    let emissive_strength = m.emissive_strength().unwrap_or(1.0);
    finite(cx, &format!("material \"{name}\" baseColorFactor"), &base)?;
    finite(
        cx,
        &format!("material \"{name}\" emissiveFactor"),
        &emissive,
    )?;
    let scalars = [
        pbr.metallic_factor(),
        pbr.roughness_factor(),
        emissive_strength,
    ];
    finite(cx, &format!("material \"{name}\" factors"), &scalars)?;
    let alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    };
    let mut out = PbrMaterial {
        name,
        // Factors are linear in glTF (only textures are sRGB-encoded).
        base_color: Vec4::from(base),
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        emissive: Vec3::from(emissive) * emissive_strength.max(0.0),
        alpha_mode,
        double_sided: m.double_sided(),
        base_color_texture: pbr
            .base_color_texture()
            .map(|t| texture_ref(cx, &t))
            .transpose()?,
        metallic_roughness_texture: (pbr.metallic_roughness_texture())
            .map(|t| texture_ref(cx, &t))
            .transpose()?,
        emissive_texture: m
            .emissive_texture()
            .map(|t| texture_ref(cx, &t))
            .transpose()?,
        ..PbrMaterial::default()
    };
    if let Some(n) = m.normal_texture() {
        out.normal_scale = n.scale();
        let (transform, tex_coord) = uv_transform(
            cx,
            n.extensions().and_then(|e| e.get(TEXTURE_TRANSFORM)),
            n.tex_coord(),
        )?;
        out.normal_texture = Some(TextureRef {
            texture: n.texture().index(),
            tex_coord,
            transform,
        });
    }
    if let Some(o) = m.occlusion_texture() {
        out.occlusion_strength = o.strength().clamp(0.0, 1.0);
        let (transform, tex_coord) = uv_transform(
            cx,
            o.extensions().and_then(|e| e.get(TEXTURE_TRANSFORM)),
            o.tex_coord(),
        )?;
        out.occlusion_texture = Some(TextureRef {
            texture: o.texture().index(),
            tex_coord,
            transform,
        });
    }
    // The gltf crate has no typed KHR_materials_anisotropy: read the JSON.
    const ANISOTROPY: &str = "KHR_materials_anisotropy";
    if let Some(a) = m.extension_value(ANISOTROPY) {
        let f = |key, default| json_f32(cx, ANISOTROPY, a, key, default);
        out.anisotropy_strength = f("anisotropyStrength", 0.0)?.clamp(0.0, 1.0);
        out.anisotropy_rotation = f("anisotropyRotation", 0.0)?;
        out.anisotropy_texture =
            json_texture_ref(cx, ANISOTROPY, a.get("anisotropyTexture"), textures)?;
    }
    // Layers over the base (passes/forward `forward.layers`), read from the JSON.
    const CLEARCOAT: &str = "KHR_materials_clearcoat";
    // Errors name the material and the extension.
    let at = |ext: &str| format!("material \"{}\": {ext}", out.name);
    if let Some(c) = m.extension_value(CLEARCOAT) {
        let ext = &at(CLEARCOAT);
        let f = |key, default| json_f32(cx, ext, c, key, default);
        let t = |key| json_texture_ref(cx, ext, c.get(key), textures);
        out.clearcoat = f("clearcoatFactor", 0.0)?.clamp(0.0, 1.0);
        out.clearcoat_roughness = f("clearcoatRoughnessFactor", 0.0)?.clamp(0.0, 1.0);
        out.clearcoat_texture = t("clearcoatTexture")?;
        out.clearcoat_roughness_texture = t("clearcoatRoughnessTexture")?;
        out.clearcoat_normal_texture = t("clearcoatNormalTexture")?;
        if let Some(n) = c.get("clearcoatNormalTexture") {
            out.clearcoat_normal_scale = json_f32(cx, ext, n, "scale", 1.0)?;
        }
    }
    out.unlit = m.extension_value("KHR_materials_unlit").is_some();
    const IOR: &str = "KHR_materials_ior";
    if let Some(i) = m.extension_value(IOR) {
        let ior = json_f32(cx, &at(IOR), i, "ior", 1.5)?;
        if ior < 1.0 {
            return Err(cx.invalid(format!(
                "material \"{}\": {IOR} ior {ior} is below 1",
                out.name
            )));
        }
        out.ior = ior;
    }
    const SHEEN: &str = "KHR_materials_sheen";
    if let Some(sh) = m.extension_value(SHEEN) {
        let ext = &at(SHEEN);
        out.sheen_color =
            json_vec3(cx, ext, sh, "sheenColorFactor", Vec3::ZERO)?.clamp(Vec3::ZERO, Vec3::ONE);
        out.sheen_roughness = json_f32(cx, ext, sh, "sheenRoughnessFactor", 0.0)?.clamp(0.0, 1.0);
        out.sheen_color_texture = json_texture_ref(cx, ext, sh.get("sheenColorTexture"), textures)?;
        out.sheen_roughness_texture =
            json_texture_ref(cx, ext, sh.get("sheenRoughnessTexture"), textures)?;
    }
    const SPECULAR: &str = "KHR_materials_specular";
    if let Some(sp) = m.extension_value(SPECULAR) {
        let ext = &at(SPECULAR);
        out.specular = json_f32(cx, ext, sp, "specularFactor", 1.0)?.clamp(0.0, 1.0);
        // Unbounded above by the extension (F0 is clamped after the ior scales it).
        out.specular_color =
            json_vec3(cx, ext, sp, "specularColorFactor", Vec3::ONE)?.max(Vec3::ZERO);
        out.specular_texture = json_texture_ref(cx, ext, sp.get("specularTexture"), textures)?;
        out.specular_color_texture =
            json_texture_ref(cx, ext, sp.get("specularColorTexture"), textures)?;
    }
    const TRANSMISSION: &str = "KHR_materials_transmission";
    if let Some(t) = m.extension_value(TRANSMISSION) {
        let ext = &at(TRANSMISSION);
        out.transmission = json_f32(cx, ext, t, "transmissionFactor", 0.0)?.clamp(0.0, 1.0);
        out.transmission_texture =
            json_texture_ref(cx, ext, t.get("transmissionTexture"), textures)?;
    }
    const VOLUME: &str = "KHR_materials_volume";
    if let Some(v) = m.extension_value(VOLUME) {
        let ext = &at(VOLUME);
        out.thickness = json_f32(cx, ext, v, "thicknessFactor", 0.0)?;
        if out.thickness < 0.0 {
            return Err(cx.invalid(format!(
                "{ext} thicknessFactor {} is negative",
                out.thickness
            )));
        }
        out.thickness_texture = json_texture_ref(cx, ext, v.get("thicknessTexture"), textures)?;
        // Absent: infinite (no absorption); the JSON cannot spell infinity.
        out.attenuation_distance = json_f32(cx, ext, v, "attenuationDistance", f32::INFINITY)?;
        if out.attenuation_distance <= 0.0 {
            return Err(cx.invalid(format!(
                "{ext} attenuationDistance {} is not positive",
                out.attenuation_distance
            )));
        }
        out.attenuation_color =
            json_vec3(cx, ext, v, "attenuationColor", Vec3::ONE)?.clamp(Vec3::ZERO, Vec3::ONE);
    }
    Ok(out)
}

/// Decodes image `index` (PNG or JPEG, from a file beside the model, a
/// buffer view, or a data URI) to RGBA8, refusing sizes over [`MAX_TEXTURE_SIZE`].
pub(super) fn image(
    cx: &GltfContext,
    img: &gltf::Image,
    buffers: &[Vec<u8>],
) -> Result<ImageData, SceneError> {
    let index = img.index();
    let (bytes, label): (std::borrow::Cow<[u8]>, String) = match img.source() {
        gltf::image::Source::View { view, .. } => {
            let data = super::buffers::view_bytes(cx, &view, buffers)?;
            (
                data.into(),
                format!("image {index} (buffer view {})", view.index()),
            )
        }
        gltf::image::Source::Uri { uri, .. } => {
            let bytes = cx.read_uri(uri)?;
            (bytes.into(), format!("image {index} \"{uri}\""))
        }
    };
    decode(cx, &bytes, &label, img.name().unwrap_or(&label))
}

fn decode(
    cx: &GltfContext,
    bytes: &[u8],
    label: &str,
    name: &str,
) -> Result<ImageData, SceneError> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| cx.invalid(format!("{label}: {e}")))?;
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| cx.invalid(format!("{label}: cannot decode: {e}")))?;
    if w == 0 || h == 0 || w > MAX_TEXTURE_SIZE || h > MAX_TEXTURE_SIZE {
        return Err(cx.invalid(format!(
            "{label}: size {w}x{h} is outside 1..={MAX_TEXTURE_SIZE} per side"
        )));
    }
    let decoded = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| cx.invalid(format!("{label}: {e}")))?
        .decode()
        .map_err(|e| cx.invalid(format!("{label}: cannot decode: {e}")))?
        .into_rgba8();
    Ok(ImageData {
        name: name.to_string(),
        width: w,
        height: h,
        rgba8: decoded.into_raw(),
    })
}

/// Linear base colour of an sRGB-encoded 8-bit texel (CPU twin for tests).
pub fn srgb8_to_linear(c: u8) -> f32 {
    srgb_to_linear(c as f32 / 255.0)
}

/// `path`'s folder, where relative URIs resolve.
pub(super) fn base_dir(path: &Path) -> &Path {
    path.parent().unwrap_or(Path::new("."))
}
