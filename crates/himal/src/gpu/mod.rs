//! GPU context: adapter choice, device, error capture, read-back.
//!
//! Validation errors and device loss never panic: wgpu's uncaptured-error
//! handler records them and [`GpuContext::check`] turns them into `Err`.

pub mod cache;
pub mod pipeline;
mod readback;
pub mod testing;

use std::sync::{Arc, Mutex};

pub use readback::{TextureData, read_buffer, read_texture};

/// Environment variable that chooses the adapter when `--adapter` is absent.
pub const ADAPTER_ENV: &str = "HIMAL_ADAPTER";

/// Device creation, validation, memory, loss and read-back failures.
#[derive(thiserror::Error, Debug)]
pub enum GpuError {
    /// No adapter of the allowed backends exists (no driver installed).
    #[error(
        "no GPU adapter found (install Mesa's software Vulkan driver: apt-get install mesa-vulkan-drivers)"
    )]
    NoAdapter,
    /// `--adapter` / [`ADAPTER_ENV`] matched no adapter.
    #[error("no adapter matches \"{wanted}\"; available: {available}")]
    NoMatchingAdapter {
        /// The name substring or backend asked for.
        wanted: String,
        /// The adapters found, separated by `; ` (`none` if there are none).
        available: String,
    },
    /// The chosen adapter refused to create a device (missing limits or features).
    #[error("could not create a device on {adapter}: {message}")]
    RequestDevice {
        /// The adapter, as [`AdapterSummary`] prints it.
        adapter: String,
        /// wgpu's error text.
        message: String,
    },
    /// wgpu reported a validation error (a bug in how the API was used).
    #[error("GPU validation error in {context}: {message}")]
    Validation {
        /// What was being done, named by the caller of [`GpuContext::check`] or [`GpuContext::scoped`].
        context: String,
        /// wgpu's error text (several errors joined by newlines).
        message: String,
    },
    /// An allocation failed for lack of GPU memory.
    #[error("GPU out of memory in {context}")]
    OutOfMemory {
        /// What was being done, named by the caller.
        context: String,
    },
    /// The device was lost (driver reset, removal); carries the reason. Recreate the context.
    #[error("GPU device lost: {0}")]
    DeviceLost(String),
    /// Copying or mapping a texture or buffer for the CPU failed; carries the cause.
    #[error("GPU read-back failed: {0}")]
    Readback(String),
    /// A shader failed to preprocess, parse, validate or reflect.
    #[error("shader: {0}")]
    Shader(#[from] crate::shader::ShaderError),
    /// Any other failure, described by its text (frame graph errors inside a pass, missing inputs).
    #[error("{0}")]
    Other(String),
}

/// What the caller asks of adapter selection.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Adapter name substring or backend name (vulkan, gl, metal, dx12);
    /// `None` reads [`ADAPTER_ENV`], then prefers hardware over software.
    pub adapter: Option<String>,
}

/// One adapter as `himal info` shows it.
#[derive(Clone, Debug)]
pub struct AdapterSummary {
    /// Adapter (GPU or driver) name as the driver reports it, e.g. `llvmpipe (LLVM 15.0.7, 256 bits)`.
    pub name: String,
    /// Graphics API it runs on (Vulkan, Metal, DX12, GL).
    pub backend: wgpu::Backend,
    /// Discrete, integrated, virtual or CPU (software) adapter.
    pub device_type: wgpu::DeviceType,
    /// Driver name and version info, joined by a space.
    pub driver: String,
}

impl std::fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({:?}, {:?}, {})",
            self.name, self.backend, self.device_type, self.driver
        )
    }
}

impl From<&wgpu::AdapterInfo> for AdapterSummary {
    fn from(i: &wgpu::AdapterInfo) -> Self {
        Self {
            name: i.name.clone(),
            backend: i.backend,
            device_type: i.device_type,
            driver: format!("{} {}", i.driver, i.driver_info).trim().to_string(),
        }
    }
}

/// The wgpu instance, chosen adapter, device and queue every pass uses, plus
/// the pipeline cache and the recorded-error log that [`Self::check`] reports.
pub struct GpuContext {
    /// The wgpu instance the adapter came from (surfaces are created from it).
    pub instance: wgpu::Instance,
    /// The chosen adapter.
    pub adapter: wgpu::Adapter,
    /// The logical device; its uncaptured errors are recorded for [`Self::check`].
    pub device: wgpu::Device,
    /// The device's only queue: submissions and `write_buffer` / `write_texture` uploads.
    pub queue: wgpu::Queue,
    /// The chosen adapter as `himal info` prints it.
    pub info: AdapterSummary,
    /// Timestamp queries inside encoders are available (per-pass timings).
    pub timestamps: bool,
    /// E1 pipeline cache: memory, then disk (`open_pipeline_cache`), then compile.
    pub pipelines: cache::ShaderCache,
    errors: Arc<Mutex<Vec<String>>>,
    lost: Arc<Mutex<Option<String>>>,
}

/// Vulkan, Metal, DX12; OpenGL only when asked for (`--adapter gl`), since
/// probing EGL headless prints errors and adds nothing where Vulkan exists.
fn backends(wanted: Option<&str>) -> wgpu::Backends {
    match wanted {
        Some(w) if w.eq_ignore_ascii_case("gl") => wgpu::Backends::GL,
        _ => wgpu::Backends::PRIMARY,
    }
}

fn new_instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    // Validation layers cost much on lavapipe; wgpu's own validation stays on.
    desc.flags = wgpu::InstanceFlags::empty();
    wgpu::Instance::new(desc)
}

/// Every adapter wgpu can see, in preference order.
pub fn adapters() -> Vec<AdapterSummary> {
    let instance = new_instance(wgpu::Backends::PRIMARY);
    let mut list = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
    sort_by_preference(&mut list);
    list.iter()
        .map(|a| AdapterSummary::from(&a.get_info()))
        .collect()
}

fn preference(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan => 0,
        wgpu::Backend::Metal | wgpu::Backend::Dx12 => 1,
        _ => 2,
    };
    (kind, backend)
}

fn sort_by_preference(list: &mut [wgpu::Adapter]) {
    list.sort_by_key(|a| preference(&a.get_info()));
}

fn matches(info: &wgpu::AdapterInfo, wanted: &str) -> bool {
    let w = wanted.to_ascii_lowercase();
    let backend = format!("{:?}", info.backend).to_ascii_lowercase();
    backend == w || info.name.to_ascii_lowercase().contains(&w)
}

impl GpuContext {
    /// Picks an adapter (see [`GpuOptions`]) and creates a device with
    /// timestamp queries when the adapter has them.
    pub fn new(options: &GpuOptions) -> Result<Self, GpuError> {
        let wanted = options
            .adapter
            .clone()
            .or_else(|| std::env::var(ADAPTER_ENV).ok().filter(|s| !s.is_empty()));
        let backends = backends(wanted.as_deref());
        let instance = new_instance(backends);
        let mut list = pollster::block_on(instance.enumerate_adapters(backends));
        sort_by_preference(&mut list);
        let adapter = match &wanted {
            Some(w) => {
                let found = list.iter().position(|a| matches(&a.get_info(), w));
                match found {
                    Some(i) => list.swap_remove(i),
                    None => {
                        let available = list
                            .iter()
                            .map(|a| AdapterSummary::from(&a.get_info()).to_string())
                            .collect::<Vec<_>>()
                            .join("; ");
                        return Err(GpuError::NoMatchingAdapter {
                            wanted: w.clone(),
                            available: if available.is_empty() {
                                "none".into()
                            } else {
                                available
                            },
                        });
                    }
                }
            }
            None => {
                if list.is_empty() {
                    return Err(GpuError::NoAdapter);
                }
                list.remove(0)
            }
        };
        let info = AdapterSummary::from(&adapter.get_info());
        let wanted_features =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let timestamps = adapter.features() & wanted_features == wanted_features;
        // PIPELINE_CACHE (Vulkan) lets compiled pipelines persist on disk (E1);
        // INDIRECT_FIRST_INSTANCE lets V6's GPU culling draw its lists indirectly.
        let optional = wgpu::Features::PIPELINE_CACHE | wgpu::Features::INDIRECT_FIRST_INSTANCE;
        let features = adapter.features() & (wanted_features | optional);
        let desc = wgpu::DeviceDescriptor {
            label: Some("himal"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|e| {
            GpuError::RequestDevice {
                adapter: info.to_string(),
                message: e.to_string(),
            }
        })?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        let lost = Arc::new(Mutex::new(None));
        let lost_sink = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut l) = lost_sink.lock() {
                *l = Some(format!("{reason:?}: {message}"));
            }
        });
        log::info!("adapter: {info}; timestamps: {timestamps}");
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            info,
            timestamps,
            pipelines: cache::ShaderCache::default(),
            errors,
            lost,
        })
    }

    /// Why the device was lost, once it has been (driver reset, removal,
    /// `Device::destroy`); a lost device stays lost: recreate the context.
    pub fn lost_reason(&self) -> Option<String> {
        self.lost.lock().ok().and_then(|l| l.clone())
    }

    /// Returns the first error recorded since the last check (device loss
    /// first), naming `context`.
    pub fn check(&self, context: &str) -> Result<(), GpuError> {
        if let Some(reason) = self.lost.lock().ok().and_then(|l| l.clone()) {
            return Err(GpuError::DeviceLost(reason));
        }
        let mut errors = self
            .errors
            .lock()
            .map_err(|_| GpuError::Other("error log poisoned".into()))?;
        if errors.is_empty() {
            return Ok(());
        }
        let message = errors.join("\n");
        errors.clear();
        if message.contains("out of memory") || message.contains("OutOfMemory") {
            return Err(GpuError::OutOfMemory {
                context: context.into(),
            });
        }
        Err(GpuError::Validation {
            context: context.into(),
            message,
        })
    }

    /// Runs `f` inside validation and out-of-memory error scopes and turns
    /// any error into `Err` naming `context` (pipeline creation, uploads).
    pub fn scoped<T>(&self, context: &str, f: impl FnOnce() -> T) -> Result<T, GpuError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = v {
            return Err(GpuError::Validation {
                context: context.into(),
                message: e.to_string(),
            });
        }
        if o.is_some() {
            return Err(GpuError::OutOfMemory {
                context: context.into(),
            });
        }
        Ok(value)
    }

    /// Blocks until the queue is idle, then reports recorded errors.
    pub fn wait(&self, context: &str) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::DeviceLost(e.to_string()))?;
        self.check(context)
    }
}

/// A single-mip 2D texture of `size` with `layers` layers (1: a plain 2D
/// texture) — the descriptor most passes, pools and tests need.
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    layers: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}
