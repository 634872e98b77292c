//! `himal view` under Xvfb (CI installs it through `./run test`): opens a
//! window on lavapipe, renders frames, writes the last one and exits.

use std::process::Command;

#[test]
fn viewer_renders_frames_under_xvfb_and_saves_a_screenshot() {
    let dir = std::env::temp_dir().join(format!("himal-view-{}", std::process::id()));
    let shot = dir.join("view.png");
    let cache = dir.join("cache");
    let out = Command::new("xvfb-run")
        .args(["-a", env!("CARGO_BIN_EXE_himal"), "view"])
        .args([
            "--size", "96x54", "--camera", "village", "--frames", "4", "--out",
        ])
        .arg(&shot)
        .env("HIMAL_CACHE_DIR", &cache)
        .output()
        .expect("xvfb-run (apt-get install xvfb; ./run test installs it)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "himal view failed:\n{stderr}");
    let img = image::open(&shot).expect("the screenshot").to_rgb8();
    assert_eq!(img.dimensions(), (96, 54));
    // A rendered village, not a blank window: sky above, ground below.
    let (top, bottom) = (img.get_pixel(48, 2), img.get_pixel(48, 52));
    assert!(
        top[2] > top[1] && bottom[1] > bottom[2],
        "{top:?} {bottom:?}"
    );
}

#[test]
fn viewer_without_a_display_says_so() {
    let out = Command::new(env!("CARGO_BIN_EXE_himal"))
        .args(["view", "--size", "8x8"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("needs a display"), "{stderr}");
}
