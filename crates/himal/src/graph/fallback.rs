//! The constants the graph binds for absent optional inputs: 1x1 textures
//! (kept by the [`super::TexturePool`]) and a buffer of zeros.

/// A constant texture the graph provides for an optional binding that is
/// absent (1x1, kept by the [`super::TexturePool`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Fallback {
    /// (1, 1, 1, 1): no occlusion, no shadow.
    White,
    /// (0, 0, 0, 0): no contribution.
    Black,
    /// A one-layer `Depth32Float` array at the far plane (1.0): an absent
    /// shadow map, nothing occludes.
    DepthFar,
    /// A 1x1x1 3D texture of zeros (an absent lookup table).
    Black3d,
    /// A one-layer 2D array of zeros (an absent clip map).
    BlackArray,
}

impl Fallback {
    /// Every fallback, in the order of their pool slots.
    pub const ALL: [Fallback; 5] = [
        Fallback::White,
        Fallback::Black,
        Fallback::DepthFar,
        Fallback::Black3d,
        Fallback::BlackArray,
    ];

    pub(crate) fn index(self) -> usize {
        self as usize
    }

    pub(crate) fn value(self) -> wgpu::Color {
        match self {
            Fallback::White => wgpu::Color::WHITE,
            Fallback::Black | Fallback::DepthFar | Fallback::Black3d | Fallback::BlackArray => {
                wgpu::Color::TRANSPARENT
            }
        }
    }

    /// Whether this fallback can fill a binding of reflected type `ty`
    /// (sample type and view dimension must match).
    pub(crate) fn fits(self, ty: &wgpu::BindingType) -> bool {
        let wgpu::BindingType::Texture {
            sample_type,
            view_dimension,
            ..
        } = ty
        else {
            return false;
        };
        let depth = matches!(sample_type, wgpu::TextureSampleType::Depth);
        match self {
            Fallback::DepthFar => depth && *view_dimension == wgpu::TextureViewDimension::D2Array,
            Fallback::White | Fallback::Black => {
                !depth && *view_dimension == wgpu::TextureViewDimension::D2
            }
            Fallback::Black3d => !depth && *view_dimension == wgpu::TextureViewDimension::D3,
            Fallback::BlackArray => {
                !depth && *view_dimension == wgpu::TextureViewDimension::D2Array
            }
        }
    }

    /// A 1x1 fallback texture (cleared to its value by the first frame).
    pub(crate) fn texture(self, device: &wgpu::Device) -> (wgpu::Texture, wgpu::TextureView) {
        let f = self;
        // Zero-initialised by wgpu; 3D textures are not render targets.
        if f == Fallback::Black3d {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("himal.fallback.Black3d"),
                size: wgpu::Extent3d {
                    width: 1,
                    height: 1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            let view = texture.create_view(&Default::default());
            return (texture, view);
        }
        let format = match f {
            Fallback::DepthFar => wgpu::TextureFormat::Depth32Float,
            Fallback::White | Fallback::Black | Fallback::Black3d | Fallback::BlackArray => {
                wgpu::TextureFormat::Rgba8Unorm
            }
        };
        let texture = crate::gpu::texture_2d(
            device,
            &format!("himal.fallback.{f:?}"),
            (1, 1),
            1,
            format,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let dimension = match f {
            Fallback::DepthFar | Fallback::BlackArray => Some(wgpu::TextureViewDimension::D2Array),
            Fallback::White | Fallback::Black | Fallback::Black3d => None,
        };
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension,
            ..Default::default()
        });
        (texture, view)
    }
}

/// Size of the graph's buffer of zeros (an absent optional buffer binding
/// may need at most this many bytes).
pub const ZERO_BUFFER_BYTES: u64 = 4096;
