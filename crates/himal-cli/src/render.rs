//! `himal render`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use himal::image_io::ImageKind;
use himal::passes::sky::bruneton::TableSizes;
use himal::scene::Scene;
use himal::{FrameSettings, Renderer, ViewBuffer};

use crate::GpuArgs;
pub use crate::options::{PostArgs, ShadowArgs};
use crate::scene_source::{is_gltf, load_scene, open_renderer};
// The view helpers moved to `camera.rs`; their old paths keep working.
pub use crate::camera::{apply_environment, pick_camera, view_camera};

#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML; one with a `[world]` table is a streamed world),
    /// `demo` (the valley) or `world` (the streamed 10 km world).
    #[arg(
        long,
        default_value = "demo",
        value_name = "FILE|demo|world",
        allow_hyphen_values = true
    )]
    pub scene: String,
    /// A glTF model (.gltf or .glb) instead of --scene, framed by an automatic camera.
    #[arg(long, value_name = "FILE", allow_hyphen_values = true)]
    pub gltf: Option<String>,
    /// An equirectangular HDR environment (.hdr or .exr) lighting the scene
    /// instead of the physical sky (replaces the scene's `[environment]`);
    /// `studio`: the built-in neutral studio (the default with --gltf);
    /// `sky`: the physical sky.
    #[arg(long, value_name = "FILE|studio|sky", allow_hyphen_values = true)]
    pub env: Option<String>,
    /// Orbit camera around the scene's bounds: degrees about +Y from the
    /// front (+Z, positive toward +X), degrees above the horizon, and the
    /// distance in metres (default: the bounds fill the view). A bare
    /// --gltf opens at 35,20.
    #[arg(long, value_name = "YAW,PITCH[,DISTANCE]", allow_hyphen_values = true)]
    pub orbit: Option<String>,
    /// With --gltf: the KHR_materials_variants variant to show (by name).
    #[arg(long, value_name = "NAME", allow_hyphen_values = true)]
    pub variant: Option<String>,
    /// glTF animation to play, by name (`none`: the rest pose; default: each
    /// file's first); an unknown name is an error listing the scene's.
    #[arg(long, value_name = "NAME|none", allow_hyphen_values = true)]
    pub animation: Option<String>,
    /// Animation clock of the first frame in seconds (later frames add 1/30 s each).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "SECONDS",
        allow_hyphen_values = true
    )]
    pub at: f32,
    /// Vertical field of view in degrees (replaces the camera's).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub fov: Option<f32>,
    /// Radiance scale of --env.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "X",
        allow_hyphen_values = true
    )]
    pub env_intensity: f32,
    /// Named camera of the scene (default: its first camera).
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    /// Time of day, HH:MM (default: the scene's).
    #[arg(long, value_name = "HH:MM", allow_hyphen_values = true)]
    pub time: Option<String>,
    /// Time-lapse: with --frames N, the sun moves from the first time to the
    /// second over the sequence while the camera stays put (each frame is a cut).
    #[arg(long, value_name = "HH:MM..HH:MM", allow_hyphen_values = true)]
    pub time_lapse: Option<String>,
    /// Image size.
    #[arg(
        long,
        default_value = "1280x720",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub size: String,
    /// Frames to render; more than one writes a numbered sequence while the camera dollies forward.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub frames: u32,
    /// Camera travel per frame in metres along its view direction (sequences).
    #[arg(long, default_value_t = 0.25, allow_hyphen_values = true)]
    pub speed: f32,
    /// Buffer to write: final or a debug view.
    #[arg(
        long,
        default_value = "final",
        value_name = "BUFFER",
        allow_hyphen_values = true
    )]
    pub view: String,
    /// Output file (.png or .exr); sequences insert _NNNN before the extension.
    #[arg(long, default_value = "out/demo.png")]
    pub out: PathBuf,
    #[command(flatten)]
    pub post: PostArgs,
    #[command(flatten)]
    pub shadows: ShadowArgs,
    /// Print each frame's log-average and adapted luminance (read back after the frame).
    #[arg(long)]
    pub print_exposure: bool,
    /// Print the compiled frame graph (passes, reads, writes) and exit.
    #[arg(long)]
    pub graph: bool,
    #[command(flatten)]
    pub ao: crate::ao::AoArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Parses `HH:MM..HH:MM` into hours.
fn parse_time_lapse(s: &str) -> Result<(f32, f32)> {
    let (a, b) = s
        .split_once("..")
        .with_context(|| format!("--time-lapse {s}: expected HH:MM..HH:MM"))?;
    let parse =
        |t: &str| himal::scene::parse_time(t).map_err(|e| anyhow::anyhow!("--time-lapse {s}: {e}"));
    Ok((parse(a)?, parse(b)?))
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("--size \"{s}\": expected WxH, e.g. 1280x720"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("--size \"{s}\": bad width"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("--size \"{s}\": bad height"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        bail!("--size {s}: width and height must be within 1..16384");
    }
    Ok((w, h))
}

impl RenderArgs {
    /// The `--gltf` model (read as glTF whatever its name ends with), else
    /// `--scene` ([`load_scene`]).
    pub fn load_scene(&self) -> Result<Scene> {
        if !self.at.is_finite() {
            bail!("--at {}: seconds, a finite number", self.at);
        }
        let mut scene = self.load_model()?;
        match self.animation.as_deref() {
            None => {}
            Some("none") => scene.set_animation(None)?,
            Some(name) => scene.set_animation(Some(name))?,
        }
        Ok(scene)
    }

    fn load_model(&self) -> Result<Scene> {
        let budget = crate::memory_budget()?;
        match (&self.gltf, &self.variant) {
            (Some(path), variant) => Ok(Scene::from_gltf_variant(
                Path::new(path),
                budget,
                variant.as_deref(),
            )?),
            (None, Some(_)) if is_gltf(&self.scene) => Ok(Scene::from_gltf_variant(
                Path::new(&self.scene),
                budget,
                self.variant.as_deref(),
            )?),
            (None, Some(v)) => bail!("--variant {v}: variants are a glTF model's (--gltf FILE)"),
            (None, None) => load_scene(&self.scene),
        }
    }

    /// The renderer for what [`Self::load_scene`] loaded: a `--gltf` model
    /// is never a world ([`open_renderer`] otherwise).
    pub fn open_renderer(&self, ctx: himal::gpu::GpuContext, scene: &Scene) -> Result<Renderer> {
        match &self.gltf {
            Some(_) => Ok(Renderer::new(ctx, scene)?),
            None => open_renderer(&self.scene, ctx, scene),
        }
    }
}

/// `--hero NAME` must name an object of the scene.
fn check_hero(scene: &Scene, hero: Option<&str>) -> Result<()> {
    let Some(name) = hero.filter(|h| *h != "off") else {
        return Ok(());
    };
    if scene.objects.iter().any(|o| o.name == name) {
        return Ok(());
    }
    let mut moving: Vec<&str> = scene
        .objects
        .iter()
        .filter(|o| o.motion.is_some())
        .map(|o| o.name.as_str())
        .collect();
    moving.dedup();
    bail!(
        "--hero {name}: the scene has no object of that name (moving objects: {})",
        if moving.is_empty() {
            "none".to_string()
        } else {
            moving.join(", ")
        }
    )
}

fn sequence_path(out: &Path, index: u32) -> PathBuf {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("frame");
    let ext = out.extension().and_then(|s| s.to_str()).unwrap_or("png");
    out.with_file_name(format!("{stem}_{index:04}.{ext}"))
}

/// The scene (with --gltf / --env applied), its camera and the frame settings
/// the options ask for (shared with `himal view`).
pub fn setup(
    args: &RenderArgs,
) -> Result<(himal::scene::Scene, himal::scene::Camera, FrameSettings)> {
    let (width, height) = parse_size(&args.size)?;
    let view: ViewBuffer = args
        .view
        .parse()
        .map_err(|e| anyhow::anyhow!("--view {}: {e}", args.view))?;
    let kind = ImageKind::from_path(&args.out)?;
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    // A dolly of more than a kilometre per frame leaves any world at once.
    if !(args.speed.is_finite() && args.speed.abs() <= 1000.0) {
        bail!(
            "--speed {}: must be a finite number of metres per frame in -1000..=1000",
            args.speed
        );
    }
    if !(args.env_intensity.is_finite() && args.env_intensity >= 0.0) {
        bail!(
            "--env-intensity {}: must be a finite scale >= 0",
            args.env_intensity
        );
    }
    let budget = crate::memory_budget()?;
    budget
        .check(
            format!("--size {}", args.size),
            u64::from(width) * u64::from(height) * himal::budget::FRAME_BYTES_PER_PIXEL,
        )
        .map_err(anyhow::Error::msg)?;
    check_output_space(&args.out, width, height, args.frames, kind)?;
    let mut scene = args.load_scene()?;
    check_hero(&scene, args.shadows.hero.as_deref())?;
    let model = args.gltf.is_some() || is_gltf(&args.scene);
    apply_environment(args, &mut scene, model);
    let camera = view_camera(args, &scene, model)?;
    let mut sun = scene.sun.clone();
    if let Some(t) = &args.time {
        sun.time_hours = himal::scene::parse_time(t).map_err(|e| anyhow::anyhow!("--time: {e}"))?;
    }
    let mut settings = FrameSettings::new(width, height, sun);
    settings.view = view;
    settings.raw = kind == ImageKind::Exr;
    args.post.apply(&mut settings)?;
    args.shadows.apply(&mut settings)?;
    args.shadows
        .apply_cinematic(&mut settings, &scene, args.camera.as_deref())?;
    settings.ao = args.ao.settings()?;
    Ok((scene, camera, settings))
}

/// A streamed world's haze in `settings` when `renderer` draws one
/// (after [`open_renderer`]).
pub fn world_haze(renderer: &Renderer, settings: &mut FrameSettings) {
    if renderer.world().is_some() {
        settings.aerial_extinction = himal::scene::world::HAZE_EXTINCTION;
    }
}

/// A sequence that cannot fit on the output's file system is refused
/// before the first frame: an error when even at 4:1 compression it would
/// not fit, a warning when uncompressed it would not.
fn check_output_space(
    out: &Path,
    width: u32,
    height: u32,
    frames: u32,
    kind: ImageKind,
) -> Result<()> {
    let per_pixel = match kind {
        ImageKind::Png => 4,
        ImageKind::Exr => 16,
    };
    let bytes = u64::from(width) * u64::from(height) * per_pixel * u64::from(frames);
    let mut dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    // The folder may not exist yet: ask the nearest one that does.
    while !dir.exists() {
        match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => dir = p,
            _ => {
                dir = Path::new(".");
                break;
            }
        }
    }
    let Some(free) = free_bytes(dir) else {
        return Ok(());
    };
    let size = himal::budget::Bytes(bytes);
    if bytes / 4 > free {
        bail!(
            "--frames {frames} at {width}x{height}: the sequence needs up to {size}, \
             and {} is left on the file system of {}",
            himal::budget::Bytes(free),
            dir.display()
        );
    }
    if bytes > free {
        log::warn!(
            "--frames {frames} at {width}x{height}: up to {size} of images, {} free on {}",
            himal::budget::Bytes(free),
            dir.display()
        );
    }
    Ok(())
}

/// Bytes free to this user on the file system holding `dir` (statvfs).
fn free_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c` is a NUL-terminated path and `st` is written by statvfs
    // before it is read (checked by the return value).
    let r = unsafe { libc::statvfs(c.as_ptr(), st.as_mut_ptr()) };
    if r != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it filled `st`.
    let st = unsafe { st.assume_init() };
    // Pseudo file systems (/proc, /sys) report no blocks at all.
    if st.f_blocks == 0 {
        return None;
    }
    // The field types differ between platforms (u32 on some 32-bit ones).
    #[allow(clippy::unnecessary_cast)]
    Some(st.f_bavail as u64 * st.f_frsize as u64)
}

/// `--sky-tables` / `--tables`: default or reference.
pub fn parse_table_sizes(s: &str) -> Result<TableSizes> {
    match s {
        "default" => Ok(TableSizes::DEFAULT),
        "reference" => Ok(TableSizes::REFERENCE),
        other => bail!("{other}: expected default or reference"),
    }
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let (scene, camera, mut settings) = setup(args)?;
    let (width, height) = (settings.width, settings.height);
    let time_lapse = args
        .time_lapse
        .as_deref()
        .map(parse_time_lapse)
        .transpose()?;
    let mut renderer = args.open_renderer(args.gpu.context()?, &scene)?;
    world_haze(&renderer, &mut settings);
    args.post.configure(&mut renderer, &args.gpu, &scene)?;
    if args.graph {
        print!("{}", renderer.describe_graph(&settings)?);
        return Ok(());
    }
    let progress = (args.frames > 1).then(|| {
        let bar = indicatif::ProgressBar::new(args.frames as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg} [{bar:40}] {pos}/{len} frames, {elapsed} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_message("rendering");
        bar
    });
    for i in 0..args.frames {
        let mut cam = camera.clone();
        if let Some((start, end)) = time_lapse {
            let f = i as f32 / (args.frames - 1).max(1) as f32;
            settings.sun.time_hours = start + (end - start) * f;
            // Hours pass between frames: no history, adaptation starts adapted.
            renderer.reset_history();
        } else {
            cam.position += cam.forward * (args.speed * i as f32);
        }
        // Animation (moving objects, sway) at 30 frames per second of sequence time.
        settings.time_s = args.at + i as f32 / 30.0;
        // Offline frames wait for every sector in range: the same image on every run.
        renderer.settle_world(&cam, std::time::Duration::from_secs(600))?;
        let frame = renderer.render(&cam, &settings)?;
        let path = if args.frames > 1 {
            sequence_path(&args.out, i)
        } else {
            args.out.clone()
        };
        himal::image_io::save(&path, &frame.image)?;
        if args.print_exposure {
            let (l_avg, l_a) = renderer.exposure_state()?;
            let line = format!("frame {i}: log-average {l_avg:.5}, adapted {l_a:.5}");
            match &progress {
                // println on a hidden bar (no terminal) would drop the line.
                Some(bar) => bar.suspend(|| println!("{line}")),
                None => println!("{line}"),
            }
        }
        match &progress {
            Some(bar) => bar.inc(1),
            None => println!(
                "wrote {} ({width}x{height}, {})",
                path.display(),
                renderer.context().info.name
            ),
        }
    }
    let stats = renderer.context().pipelines.stats();
    crate::save_cache(renderer.context());
    if let Some(bar) = progress {
        bar.finish_with_message(format!(
            "wrote {} frames next to {}",
            args.frames,
            args.out.display()
        ));
    }
    println!("pipelines: {stats}");
    Ok(())
}
