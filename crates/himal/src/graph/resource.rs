//! Resource descriptions, typed versioned handles and access kinds.

use std::fmt;

/// Description of a graph texture (transient or imported).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct TextureDesc {
    /// wgpu label; the resource name is used when `None`.
    pub label: Option<String>,
    /// Width in texels of mip 0.
    pub width: u32,
    /// Height in texels of mip 0.
    pub height: u32,
    /// Depth (3D) or array layers (2D); 1 for a plain 2D texture.
    pub depth_or_layers: u32,
    /// Number of mip levels, at least 1.
    pub mip_levels: u32,
    /// Texel format.
    pub format: wgpu::TextureFormat,
    /// 1D, 2D or 3D.
    pub dimension: wgpu::TextureDimension,
}

impl TextureDesc {
    /// A single-layer, single-mip 2D texture.
    pub fn new_2d(width: u32, height: u32, format: wgpu::TextureFormat) -> Self {
        Self {
            label: None,
            width,
            height,
            depth_or_layers: 1,
            mip_levels: 1,
            format,
            dimension: wgpu::TextureDimension::D2,
        }
    }

    /// Reads the description back from an existing texture (imports).
    pub fn from_texture(texture: &wgpu::Texture) -> Self {
        Self {
            label: None,
            width: texture.width(),
            height: texture.height(),
            depth_or_layers: texture.depth_or_array_layers(),
            mip_levels: texture.mip_level_count(),
            format: texture.format(),
            dimension: texture.dimension(),
        }
    }

    /// Width, height and depth/layers as a wgpu extent (mip 0).
    pub fn size(&self) -> wgpu::Extent3d {
        wgpu::Extent3d {
            width: self.width,
            height: self.height,
            depth_or_array_layers: self.depth_or_layers,
        }
    }

    /// Approximate bytes of all mips (no driver padding): used for pool statistics.
    pub fn byte_size(&self) -> u64 {
        let (bw, bh) = self.format.block_dimensions();
        // Depth/stencil formats have no copy size for the combined aspect.
        let block_bytes = self
            .format
            .block_copy_size(None)
            .unwrap_or(match self.format {
                wgpu::TextureFormat::Depth16Unorm | wgpu::TextureFormat::Stencil8 => 2,
                wgpu::TextureFormat::Depth32FloatStencil8 => 8,
                _ => 4,
            }) as u64;
        (0..self.mip_levels.max(1))
            .map(|level| {
                let e = self.size().mip_level_size(level, self.dimension);
                let blocks_x = e.width.div_ceil(bw) as u64;
                let blocks_y = e.height.div_ceil(bh) as u64;
                blocks_x * blocks_y * e.depth_or_array_layers as u64 * block_bytes
            })
            .sum()
    }
}

/// Description of a graph buffer.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct BufferDesc {
    /// wgpu label; the resource name is used when `None`.
    pub label: Option<String>,
    /// Size in bytes.
    pub size: u64,
    /// Usages added to the derived ones (e.g. `COPY_SRC` for a debug dump
    /// performed outside the graph).
    pub extra_usages: wgpu::BufferUsages,
}

impl BufferDesc {
    /// A buffer of `size` bytes, no label and no extra usages.
    pub fn new(size: u64) -> Self {
        Self {
            label: None,
            size,
            extra_usages: wgpu::BufferUsages::empty(),
        }
    }

    /// Reads the description back from an existing buffer (imports).
    pub fn from_buffer(buffer: &wgpu::Buffer) -> Self {
        Self {
            label: None,
            size: buffer.size(),
            extra_usages: wgpu::BufferUsages::empty(),
        }
    }
}

/// A texture at one version. Writing through a [`super::PassBuilder`]
/// returns the next version; handles are only valid in the graph that made them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureHandle {
    pub(crate) graph: u32,
    pub(crate) index: u32,
    pub(crate) version: u32,
}

/// A buffer at one version; see [`TextureHandle`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BufferHandle {
    pub(crate) graph: u32,
    pub(crate) index: u32,
    pub(crate) version: u32,
}

impl TextureHandle {
    /// 0 = not yet written (imported resources: the external content).
    pub fn version(&self) -> u32 {
        self.version
    }
}

impl BufferHandle {
    /// 0 = not yet written (imported resources: the external content).
    pub fn version(&self) -> u32 {
        self.version
    }
}

/// How a pass uses a texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextureAccess {
    /// Read through a sampled texture binding.
    Sampled,
    /// Read through a read-only storage texture binding.
    StorageRead,
    /// Written through a storage texture binding (compute).
    StorageWrite,
    /// Rendered to as a colour attachment.
    ColorAttachment,
    /// Depth-tested and written as the depth attachment.
    DepthAttachment,
    /// Read-only depth attachment (depth test without depth write).
    DepthRead,
    /// Source of a copy.
    CopySrc,
    /// Destination of a copy (upload or texture-to-texture).
    CopyDst,
}

impl TextureAccess {
    /// The wgpu usage flag this access needs.
    pub fn usage(self) -> wgpu::TextureUsages {
        use wgpu::TextureUsages as U;
        match self {
            Self::Sampled => U::TEXTURE_BINDING,
            Self::StorageRead | Self::StorageWrite => U::STORAGE_BINDING,
            Self::ColorAttachment | Self::DepthAttachment | Self::DepthRead => U::RENDER_ATTACHMENT,
            Self::CopySrc => U::COPY_SRC,
            Self::CopyDst => U::COPY_DST,
        }
    }

    /// Whether this access may be declared with `write` (else with `read`).
    pub fn is_write(self) -> bool {
        matches!(
            self,
            Self::StorageWrite | Self::ColorAttachment | Self::DepthAttachment | Self::CopyDst
        )
    }
}

/// How a pass uses a buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BufferAccess {
    /// Bound as a uniform buffer.
    Uniform,
    /// Bound as a read-only storage buffer.
    StorageRead,
    /// Bound as a read-write storage buffer.
    StorageWrite,
    /// Source of a copy (e.g. a readback).
    CopySrc,
    /// Destination of a copy or `write_buffer`.
    CopyDst,
    /// Bound as a vertex buffer.
    Vertex,
    /// Bound as an index buffer.
    Index,
    /// Holds indirect draw or dispatch arguments.
    Indirect,
}

impl BufferAccess {
    /// The wgpu usage flag this access needs.
    pub fn usage(self) -> wgpu::BufferUsages {
        use wgpu::BufferUsages as U;
        match self {
            Self::Uniform => U::UNIFORM,
            Self::StorageRead | Self::StorageWrite => U::STORAGE,
            Self::CopySrc => U::COPY_SRC,
            Self::CopyDst => U::COPY_DST,
            Self::Vertex => U::VERTEX,
            Self::Index => U::INDEX,
            Self::Indirect => U::INDIRECT,
        }
    }

    /// Whether this access may be declared with `write_buffer`.
    pub fn is_write(self) -> bool {
        matches!(self, Self::StorageWrite | Self::CopyDst)
    }
}

/// A texture or buffer access, as listed by [`super::CompiledPass`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ResourceAccess {
    /// An access to a texture.
    Texture(TextureAccess),
    /// An access to a buffer.
    Buffer(BufferAccess),
}

impl ResourceAccess {
    pub(crate) fn is_write(self) -> bool {
        match self {
            Self::Texture(a) => a.is_write(),
            Self::Buffer(a) => a.is_write(),
        }
    }
}

impl fmt::Display for ResourceAccess {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Texture(a) => write!(f, "{a:?}"),
            Self::Buffer(a) => write!(f, "{a:?}"),
        }
    }
}

/// One declared use of a resource version by a pass.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ResourceUse {
    /// Name of the resource.
    pub resource: String,
    /// Version read, or for writes the new version produced.
    pub version: u32,
    /// How the pass uses it.
    pub access: ResourceAccess,
}

impl fmt::Display for ResourceUse {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}@{} ({})", self.resource, self.version, self.access)
    }
}

/// Derived usages of a texture or buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Usages {
    Texture(wgpu::TextureUsages),
    Buffer(wgpu::BufferUsages),
}

/// `A | B` names of a flags value, "none" when empty.
pub(crate) fn flag_names<'f>(names: impl Iterator<Item = (&'f str, impl Sized)>) -> String {
    let list: Vec<&str> = names.map(|(n, _)| n).collect();
    if list.is_empty() {
        "none".to_string()
    } else {
        list.join(" | ")
    }
}

impl fmt::Display for Usages {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Texture(u) => f.write_str(&flag_names(u.iter_names())),
            Self::Buffer(u) => f.write_str(&flag_names(u.iter_names())),
        }
    }
}
