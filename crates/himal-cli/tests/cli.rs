//! The `himal` program: bad input gives a non-zero exit and a clear message.

mod common;

fn himal(args: &[&str]) -> (bool, String, String) {
    // Tests never touch the user's pipeline cache.
    let cache = common::temp_path("cli-cache");
    common::run(args, &[("HIMAL_CACHE_DIR", cache.as_os_str())])
}

fn fails_with(args: &[&str], needle: &str) {
    common::assert_fails_with(args, &himal(args), needle);
}

#[test]
fn size_zero_is_rejected() {
    fails_with(&["render", "--size", "0x0"], "--size 0x0");
}

#[test]
fn unknown_camera_lists_known_ones() {
    fails_with(
        &["render", "--camera", "nowhere", "--size", "8x8"],
        "nowhere",
    );
}

#[test]
fn bad_time_is_rejected() {
    fails_with(&["render", "--time", "25:99", "--size", "8x8"], "--time");
}

#[test]
fn bad_view_lists_views() {
    fails_with(
        &["render", "--view", "nope", "--size", "8x8"],
        "known: final",
    );
}

#[test]
fn unwritable_output_names_the_file() {
    fails_with(
        &["render", "--size", "8x8", "--out", "/proc/himal-test/x.png"],
        "/proc/himal-test/x.png",
    );
}

#[test]
fn malformed_scene_names_file_and_line() {
    let dir = common::temp_path("cli-test");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("broken.toml");
    std::fs::write(
        &path,
        "[sun]\ntime = \"10:00\"\n\n[[object]\nname = \"x\"\n",
    )
    .expect("write");
    let p = path.to_string_lossy().to_string();
    fails_with(&["render", "--scene", &p, "--size", "8x8"], "broken.toml:4");
}

#[test]
fn graph_lists_passes_in_order() {
    let (ok, out, err) = himal(&["render", "--graph", "--size", "64x36"]);
    assert!(ok, "{err}");
    // The demo's fox is posed first (skin, then its copy into the vertices).
    let order = [
        "skin",
        "skin.copy",
        "gbuffer",
        "lighting.deferred",
        "sky",
        "post.luminance",
        "post.tonemap",
    ];
    let mut at = 0;
    for id in order {
        let i = out[at..]
            .find(id)
            .unwrap_or_else(|| panic!("{id} missing or out of order in:\n{out}"));
        at += i + id.len();
    }
}

#[test]
fn renders_a_png() {
    let dir = common::temp_path("cli-png");
    let path = dir.join("f.png");
    let p = path.to_string_lossy().to_string();
    let (ok, _, err) = himal(&[
        "render",
        "--size",
        "64x36",
        "--camera",
        "materials",
        "--out",
        &p,
    ]);
    assert!(ok, "{err}");
    let img = image::open(&path).expect("a PNG");
    assert_eq!((img.width(), img.height()), (64, 36));
}

#[test]
fn time_lapse_writes_a_day_sequence() {
    let dir = common::temp_path("cli-lapse");
    let p = dir.join("day.png").to_string_lossy().to_string();
    let (ok, _, err) = himal(&[
        "render",
        "--size",
        "48x27",
        "--camera",
        "village",
        "--frames",
        "3",
        "--time-lapse",
        "07:00..19:00",
        "--out",
        &p,
    ]);
    assert!(ok, "{err}");
    let frames: Vec<_> = (0..3)
        .map(|i| {
            image::open(dir.join(format!("day_{i:04}.png")))
                .expect("a frame")
                .to_rgb8()
        })
        .collect();
    // Morning, noon and evening light differ (sun direction and colour).
    assert_ne!(frames[0].as_raw(), frames[1].as_raw());
    assert_ne!(frames[1].as_raw(), frames[2].as_raw());
    fails_with(&["render", "--time-lapse", "07:00-19:00"], "HH:MM..HH:MM");
}

#[test]
fn env_lights_the_demo_with_an_hdr_image() {
    let dir = common::temp_path("cli-env");
    let p = dir.join("env.png").to_string_lossy().to_string();
    let venice = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/assets/env/venice_sunset_1k.hdr"
    );
    let (ok, _, err) = himal(&[
        "render", "--size", "48x27", "--camera", "village", "--env", venice, "--out", &p,
    ]);
    assert!(ok, "{err}");
    assert!(image::open(&p).is_ok());
    fails_with(
        &["render", "--size", "8x8", "--env", "/nowhere/sky.hdr"],
        "/nowhere/sky.hdr",
    );
}

#[test]
fn numeric_options_out_of_range_say_the_allowed_range() {
    // Negative values reach the check (not clap's "unexpected argument").
    fails_with(
        &["render", "--ao-radius", "-1"],
        "--ao-radius -1: must be a number of metres in (0, 100]",
    );
    fails_with(
        &["render", "--ssdo-strength", "-0.5"],
        "--ssdo-strength -0.5: must be in [0, 1]",
    );
    fails_with(
        &["render", "--reflection-occlusion", "maybe"],
        "--reflection-occlusion maybe: expected on or off",
    );
    fails_with(&["render", "--ao", "sdo"], "ssdo");
    fails_with(
        &["render", "--speed", "nan"],
        "--speed NaN: must be a finite",
    );
    fails_with(&["render", "--speed", "1e30"], "in -1000..=1000");
    fails_with(&["render", "--speed", "-inf"], "--speed -inf");
    fails_with(
        &["render", "--env-intensity", "-2"],
        "--env-intensity -2: must be a finite scale >= 0",
    );
}

#[test]
fn a_shadow_map_too_large_for_one_texture_is_refused_before_the_frame() {
    // 4 x 16384² x 4 B = 4 GiB: the driver's raw "texture is invalid" before.
    let out = common::temp_path("huge-shadow").with_extension("png");
    let out = out.to_str().expect("utf-8 temp path");
    let args = [
        "render",
        "--size",
        "16x16",
        "--shadow-resolution",
        "16384",
        "--out",
        out,
    ];
    fails_with(&args, "shadow resolution 16384 needs 4.0 GiB");
}

/// `--gltf` reads its file as glTF whatever the name ends with (issue #22:
/// `--gltf README.md` was parsed as a TOML scene, a `.json` model refused).
#[test]
fn gltf_flag_reads_any_name_as_gltf() {
    let dir = common::temp_path("cli-gltf-name");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let model = dir.join("triangle.json");
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,B64"}],
"bufferViews":[{"buffer":0,"byteLength":36}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}"#;
    std::fs::write(
        &model,
        json.replace("B64", "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"),
    )
    .expect("write model");
    let out = dir.join("t.png");
    let (m, o) = (model.to_string_lossy(), out.to_string_lossy());
    let (ok, _, err) = himal(&["render", "--gltf", &m, "--size", "32x32", "--out", &o]);
    assert!(ok, "{err}");
    assert!(image::open(&out).is_ok(), "a PNG");
    // A text file is a glTF error naming it, not a TOML one.
    let text = dir.join("notes.md");
    std::fs::write(&text, "# notes\n").expect("write");
    let t = text.to_string_lossy();
    let args = ["render", "--gltf", &*t, "--size", "8x8", "--out", &*o];
    let (ok, _, err) = himal(&args);
    assert!(!ok, "a text file rendered as glTF");
    assert!(err.contains("notes.md") && err.contains("glTF"), "{err}");
    assert!(!err.to_lowercase().contains("toml"), "{err}");
}

/// `bench --json` is one JSON document on standard output (it used to
/// print the one-off sky-table lines first); its total is the sum of the
/// passes' per-frame costs (per-run cost x runs / frames), and the CSV
/// holds the same rows.
#[test]
fn bench_json_is_json_alone() {
    let csv = common::temp_path("bench.csv");
    let c = csv.to_string_lossy();
    let args = [
        "bench", "--json", "--frames", "3", "--size", "32x18", "--csv", &*c,
    ];
    let (ok, out, err) = himal(&args);
    assert!(ok, "himal {args:?} failed: {err}");
    let v: serde_json::Value = serde_json::from_str(&out)
        .unwrap_or_else(|e| panic!("bench --json stdout is not JSON ({e}):\n{out}"));
    let passes = v["passes"].as_array().expect("passes");
    assert!(!passes.is_empty(), "no passes in {out}");
    assert!(
        v["one_off"].as_array().is_some_and(|o| !o.is_empty()),
        "the sky tables' one-off times belong in the JSON: {out}"
    );
    let num = |p: &serde_json::Value, k: &str| p[k].as_f64().unwrap_or_else(|| panic!("{k}: {p}"));
    for p in passes {
        let (runs, frames) = (num(p, "runs"), num(p, "frames"));
        assert!(runs >= 1.0 && runs <= frames && frames == 3.0, "{p}");
        // Rounded to 4 decimals in the JSON.
        let counted = num(p, "run_ms") * runs / frames;
        assert!((counted - num(p, "frame_ms")).abs() < 1e-3, "{p}");
        let timing = p["timing"].as_str().expect("timing");
        assert!(
            ["encoder-ts", "pass-ts", "isolated-wall"].contains(&timing),
            "{p}"
        );
    }
    let sum: f64 = passes.iter().map(|p| num(p, "frame_ms")).sum();
    let total = v["gpu_frame_ms"].as_f64().expect("gpu_frame_ms");
    assert!(
        (sum - total).abs() < 1e-3 * passes.len() as f64,
        "{sum} vs {total}"
    );
    let cpu = &v["cpu_ms_median"];
    for k in [
        "total", "thread", "plan", "cull", "upload", "record", "submit",
    ] {
        assert!(cpu[k].as_f64().is_some_and(|x| x >= 0.0), "cpu {k}: {out}");
    }
    let text = std::fs::read_to_string(&csv).expect("bench --csv wrote the file");
    let _ = std::fs::remove_file(&csv);
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines[0].starts_with("pass,group,timing,run_ms,runs,frames,frame_ms"),
        "{text}"
    );
    assert_eq!(lines.len(), passes.len() + 1, "{text}");
}

/// `bench --compare A B` runs both sides interleaved and prints each
/// pass's per-frame cost on both, the ratio and its spread: AO passes on
/// the `hbao` side only.
#[test]
fn bench_compare_runs_two_settings_interleaved() {
    // Shadows off and small maps keep it quick: the base options apply to both sides.
    let args = [
        "bench",
        "--compare",
        "--ao off",
        "--ao hbao",
        "--frames",
        "4",
        "--size",
        "32x18",
        "--json",
        "--isolation-frames",
        "1",
        "--shadows",
        "off",
    ];
    let (ok, out, err) = himal(&args);
    assert!(ok, "himal {args:?} failed: {err}");
    let v: serde_json::Value = serde_json::from_str(&out)
        .unwrap_or_else(|e| panic!("bench --compare --json stdout is not JSON ({e}):\n{out}"));
    assert_eq!(v["blocks"].as_u64(), Some(4), "{out}");
    let passes = v["passes"].as_array().expect("passes");
    let hbao = passes
        .iter()
        .find(|p| p["id"] == "ao.hbao")
        .unwrap_or_else(|| panic!("no ao.hbao row: {out}"));
    assert_eq!(hbao["a_ms"].as_f64(), Some(0.0), "{hbao}");
    assert!(hbao["b_ms"].as_f64().is_some_and(|b| b > 0.0), "{hbao}");
    let gbuffer = passes
        .iter()
        .find(|p| p["id"] == "gbuffer")
        .expect("gbuffer");
    let spread = &gbuffer["block_ratio"];
    let q = |k: &str| {
        spread[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k}: {gbuffer}"))
    };
    assert!(
        q("q1") <= q("median") && q("median") <= q("q3"),
        "{gbuffer}"
    );
    // At 32x18 the AO is far inside the frame's noise: a ratio, not its side of 1.
    assert!(
        v["frame"]["ratio"].as_f64().is_some_and(|r| r > 0.0),
        "{out}"
    );
    assert!(v["cpu"]["a_ms"].as_f64().is_some(), "{out}");
    // The table names both sides; a bad side names itself.
    let (ok, out, err) = himal(&[
        "bench",
        "--compare",
        "--ao off",
        "",
        "--frames",
        "1",
        "--size",
        "16x16",
        "--shadows",
        "off",
        "--isolation-frames",
        "0",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("B/A") && out.contains("frame GPU"), "{out}");
    let bad = ["bench", "--compare", "--ao off", "--no-such"];
    common::assert_fails_with(&bad, &himal(&bad), "--compare B");
}

/// `./run` looked for a Vulkan driver with one `ls` over two globs, which
/// fails when either folder is empty: with lavapipe in /usr/share and an
/// empty /etc/vulkan/icd.d, every call ran apt.
#[test]
fn run_finds_a_vulkan_driver_beside_an_empty_folder() {
    let dir = common::temp_path("run-icd");
    let (empty, full) = (dir.join("etc"), dir.join("share"));
    std::fs::create_dir_all(&empty).expect("temp dir");
    std::fs::create_dir_all(&full).expect("temp dir");
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../../run");
    let doctor = |dirs: String| {
        let out = std::process::Command::new("bash")
            .args([script, "doctor"])
            .env("HIMAL_VULKAN_ICD_DIRS", dirs)
            .output()
            .expect("runs ./run doctor");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let both = format!("{} {}", full.display(), empty.display());
    let reversed = format!("{} {}", empty.display(), full.display());
    let none = doctor(both.clone());
    assert!(none.contains("vulkan driver: none"), "{none}");
    let icd = full.join("lvp_icd.x86_64.json");
    std::fs::write(&icd, "{}").expect("write manifest");
    for dirs in [both, reversed] {
        let found = doctor(dirs);
        assert!(
            found.contains(&format!("vulkan driver: {}", icd.display())),
            "{found}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn tonemap_flag_names_the_curves_and_keeps_the_white_point_reinhards() {
    fails_with(
        &["render", "--tonemap", "filmic", "--size", "8x8"],
        "reinhard, neutral, aces, agx",
    );
    fails_with(
        &[
            "render",
            "--tonemap",
            "agx",
            "--white-point",
            "4",
            "--size",
            "8x8",
        ],
        "--white-point is Reinhard's",
    );
}

/// --orbit and --fov frame a model as another viewer's camera would; bad
/// values are named.
#[test]
fn orbit_and_fov_are_checked() {
    let out = common::temp_path("orbit").with_extension("png");
    let out = out.to_string_lossy();
    let args = [
        "render",
        "--gltf",
        "builtin:DamagedHelmet.glb",
        "--orbit",
        "30,20,4",
        "--fov",
        "35",
        "--size",
        "32x32",
        "--out",
        &out,
    ];
    let (ok, _, err) = himal(&args);
    assert!(ok, "{err}");
    std::fs::remove_file(&*out).ok();
    fails_with(
        &["render", "--orbit", "30", "--size", "8x8"],
        "YAW,PITCH[,DISTANCE]",
    );
    fails_with(
        &["render", "--orbit", "0,95", "--size", "8x8"],
        "within ±89.9",
    );
    fails_with(
        &["render", "--orbit", "0,0,-1", "--size", "8x8"],
        "distance must be positive",
    );
    fails_with(
        &[
            "render", "--orbit", "0,0", "--camera", "village", "--size", "8x8",
        ],
        "leave out --camera",
    );
    fails_with(&["render", "--fov", "0", "--size", "8x8"], "--fov 0");
}

#[test]
fn variant_names_the_files_variants() {
    let chair = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/assets/gltf/SheenChair/glTF/SheenChair.gltf"
    );
    fails_with(
        &[
            "render",
            "--gltf",
            chair,
            "--variant",
            "Tartan",
            "--size",
            "8x8",
        ],
        "Mango Velvet, Peacock Velvet",
    );
    fails_with(
        &["render", "--variant", "Tartan", "--size", "8x8"],
        "variants are a glTF model's",
    );
}

#[test]
fn animation_names_the_scenes_clips_and_at_is_checked() {
    let fox = "builtin:Fox.glb";
    let args = [
        "render",
        "--gltf",
        fox,
        "--size",
        "8x8",
        "--animation",
        "Swim",
    ];
    fails_with(
        &args,
        "no animation \"Swim\" (the scene's: Survey, Walk, Run)",
    );
    let helmet = [
        "render",
        "--gltf",
        "builtin:DamagedHelmet.glb",
        "--size",
        "8x8",
    ];
    fails_with(
        &[&helmet[..], &["--animation", "Walk"]].concat(),
        "the scene has no animations",
    );
    fails_with(
        &["render", "--gltf", fox, "--size", "8x8", "--at", "nan"],
        "--at NaN",
    );
}

#[test]
fn bad_particle_switches_are_rejected() {
    fails_with(
        &["render", "--particles", "maybe", "--size", "8x8"],
        "--particles",
    );
    fails_with(
        &["render", "--particle-lighting", "corner", "--size", "8x8"],
        "--particle-lighting corner",
    );
    fails_with(
        &["render", "--particle-ambient", "cube", "--size", "8x8"],
        "--particle-ambient cube",
    );
    fails_with(
        &["render", "--particle-shadows", "dynamic", "--size", "8x8"],
        "--particle-shadows dynamic",
    );
    fails_with(
        &["render", "--particle-sort", "maybe", "--size", "8x8"],
        "--particle-sort",
    );
    fails_with(
        &["render", "--particle-reactive", "maybe", "--size", "8x8"],
        "--particle-reactive",
    );
}

#[test]
fn bad_shadow_mask_switches_are_rejected() {
    fails_with(
        &["render", "--shadow-hero-scissor", "maybe", "--size", "8x8"],
        "--shadow-hero-scissor maybe",
    );
    fails_with(
        &["render", "--shadow-mask-tiles", "2", "--size", "8x8"],
        "--shadow-mask-tiles 2",
    );
    fails_with(
        &["render", "--shadow-alpha-test", "maybe", "--size", "8x8"],
        "--shadow-alpha-test maybe",
    );
}

#[test]
fn bad_deform_motion_switch_is_rejected() {
    fails_with(
        &["render", "--deform-motion", "maybe", "--size", "8x8"],
        "--deform-motion",
    );
}

#[test]
fn bad_vegetation_switch_is_rejected() {
    fails_with(
        &["render", "--vegetation", "maybe", "--size", "8x8"],
        "--vegetation",
    );
    fails_with(
        &["bench", "--vegetation", "some", "--size", "8x8"],
        "--vegetation",
    );
}

#[test]
fn bad_ao_bleed_ambient_lights_and_wetness_are_rejected() {
    fails_with(
        &["render", "--ao-bleed", "maybe", "--size", "8x8"],
        "--ao-bleed maybe",
    );
    fails_with(
        &["render", "--ambient-lights", "2", "--size", "8x8"],
        "--ambient-lights",
    );
    fails_with(
        &["render", "--wetness", "1.5", "--size", "8x8"],
        "--wetness 1.5",
    );
    fails_with(
        &["render", "--wetness", "nan", "--size", "8x8"],
        "--wetness",
    );
}

#[test]
fn too_many_ambient_lights_name_the_file() {
    let dir = common::temp_path("cli-ambient");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("ambient.toml");
    let table = "[[ambient_light]]\nposition = [0.0, 0.0, 0.0]\nradius = 1.0\nfactor = 0.5\n";
    std::fs::write(&path, table.repeat(65)).expect("write");
    let p = path.to_string_lossy().to_string();
    fails_with(&["render", "--scene", &p, "--size", "8x8"], "ambient.toml");
    fails_with(&["render", "--scene", &p, "--size", "8x8"], "at most 64");
}
