//! Bind-group layouts reflected from a composed module's globals, so a
//! layout is never written twice (once in WGSL, once in Rust).
//!
//! Conventions the WGSL follows: float textures are filterable unless the
//! binding name ends in `_load` (read only with `textureLoad`, e.g. R32Float);
//! `sampler_comparison` is a comparison sampler, other samplers filter.

use super::{ComposedShader, ShaderError};

/// One global resource binding declared in the WGSL.
#[derive(Clone, Debug)]
pub struct BindingInfo {
    /// The WGSL variable name; bind groups are built by this name.
    pub name: String,
    /// `@group` index.
    pub group: u32,
    /// `@binding` index within the group.
    pub binding: u32,
    /// The wgpu binding type derived from the WGSL type (see the module docs for the conventions).
    pub ty: wgpu::BindingType,
}

/// The bind-group layouts of a composed shader, reflected from its global bindings.
#[derive(Clone, Debug)]
pub struct ReflectedLayout {
    /// Bindings per group index, sorted by binding number.
    pub groups: Vec<Vec<BindingInfo>>,
    /// Stages of the module's entry points; every binding is made visible to all of them.
    pub visibility: wgpu::ShaderStages,
}

impl ReflectedLayout {
    /// Layout entries of group `group` (empty for a group the shader does not use).
    pub fn entries(&self, group: usize) -> Vec<wgpu::BindGroupLayoutEntry> {
        self.groups
            .get(group)
            .map(|g| {
                g.iter()
                    .map(|b| wgpu::BindGroupLayoutEntry {
                        binding: b.binding,
                        visibility: self.visibility,
                        ty: b.ty,
                        count: None,
                    })
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The binding named `name` in any group.
    pub fn find(&self, name: &str) -> Option<&BindingInfo> {
        self.groups.iter().flatten().find(|b| b.name == name)
    }
}

fn storage_format(f: naga::StorageFormat) -> Option<wgpu::TextureFormat> {
    use naga::StorageFormat as S;
    use wgpu::TextureFormat as T;
    Some(match f {
        S::Rgba8Unorm => T::Rgba8Unorm,
        S::Rgba8Snorm => T::Rgba8Snorm,
        S::Rgba16Float => T::Rgba16Float,
        S::Rgba32Float => T::Rgba32Float,
        S::R32Float => T::R32Float,
        S::R32Uint => T::R32Uint,
        S::Rg32Float => T::Rg32Float,
        S::Rgb10a2Unorm => T::Rgb10a2Unorm,
        S::Rg16Float => T::Rg16Float,
        S::R16Float => T::R16Float,
        S::Rgba32Uint => T::Rgba32Uint,
        S::Rgba16Unorm => T::Rgba16Unorm,
        _ => return None,
    })
}

fn view_dimension(dim: naga::ImageDimension, arrayed: bool) -> wgpu::TextureViewDimension {
    use naga::ImageDimension as D;
    use wgpu::TextureViewDimension as V;
    match (dim, arrayed) {
        (D::D1, _) => V::D1,
        (D::D2, false) => V::D2,
        (D::D2, true) => V::D2Array,
        (D::D3, _) => V::D3,
        (D::Cube, false) => V::Cube,
        (D::Cube, true) => V::CubeArray,
    }
}

pub(super) fn reflect(shader: &ComposedShader) -> Result<ReflectedLayout, ShaderError> {
    let module = &shader.module;
    let err = |message: String| ShaderError::Reflection {
        shader: shader.name.clone(),
        message,
    };
    let mut visibility = wgpu::ShaderStages::empty();
    for ep in &module.entry_points {
        visibility |= match ep.stage {
            naga::ShaderStage::Vertex => wgpu::ShaderStages::VERTEX,
            naga::ShaderStage::Fragment => wgpu::ShaderStages::FRAGMENT,
            naga::ShaderStage::Compute => wgpu::ShaderStages::COMPUTE,
            _ => wgpu::ShaderStages::empty(),
        };
    }
    let mut layout = ReflectedLayout {
        groups: Vec::new(),
        visibility,
    };
    for (_, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let name = var.name.clone().unwrap_or_default();
        let inner = &module.types[var.ty].inner;
        let ty = match (var.space, inner) {
            (naga::AddressSpace::Uniform, _) => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            (naga::AddressSpace::Storage { access }, _) => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage {
                    read_only: !access.contains(naga::StorageAccess::STORE),
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            (_, naga::TypeInner::Sampler { comparison }) => {
                wgpu::BindingType::Sampler(if *comparison {
                    wgpu::SamplerBindingType::Comparison
                } else {
                    wgpu::SamplerBindingType::Filtering
                })
            }
            (
                _,
                naga::TypeInner::Image {
                    dim,
                    arrayed,
                    class,
                },
            ) => {
                let view_dimension = view_dimension(*dim, *arrayed);
                match class {
                    naga::ImageClass::Sampled { kind, multi } => wgpu::BindingType::Texture {
                        sample_type: match kind {
                            naga::ScalarKind::Sint => wgpu::TextureSampleType::Sint,
                            naga::ScalarKind::Uint => wgpu::TextureSampleType::Uint,
                            _ => wgpu::TextureSampleType::Float {
                                filterable: !name.ends_with("_load"),
                            },
                        },
                        view_dimension,
                        multisampled: *multi,
                    },
                    naga::ImageClass::Depth { multi } => wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension,
                        multisampled: *multi,
                    },
                    naga::ImageClass::Storage { format, access } => {
                        wgpu::BindingType::StorageTexture {
                            access: match (
                                access.contains(naga::StorageAccess::LOAD),
                                access.contains(naga::StorageAccess::STORE),
                            ) {
                                (true, true) => wgpu::StorageTextureAccess::ReadWrite,
                                (true, false) => wgpu::StorageTextureAccess::ReadOnly,
                                _ => wgpu::StorageTextureAccess::WriteOnly,
                            },
                            format: storage_format(*format).ok_or_else(|| {
                                err(format!("{name}: unsupported storage format {format:?}"))
                            })?,
                            view_dimension,
                        }
                    }
                    naga::ImageClass::External => {
                        return Err(err(format!("{name}: external textures are not supported")));
                    }
                }
            }
            (space, _) => return Err(err(format!("{name}: unsupported binding in {space:?}"))),
        };
        let g = rb.group as usize;
        if layout.groups.len() <= g {
            layout.groups.resize(g + 1, Vec::new());
        }
        layout.groups[g].push(BindingInfo {
            name,
            group: rb.group,
            binding: rb.binding,
            ty,
        });
    }
    for g in &mut layout.groups {
        g.sort_by_key(|b| b.binding);
    }
    Ok(layout)
}
