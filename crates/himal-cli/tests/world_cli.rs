//! `himal bench --scene world --path NAME`: the flight's per-frame report
//! holds what streaming, culling and LOD did (issue #17).

mod common;

fn himal(args: &[&str]) -> (bool, String, String) {
    let cache = common::temp_path("world-cli-cache");
    common::run(args, &[("HIMAL_CACHE_DIR", cache.as_os_str())])
}

/// The CSV's rows as (header -> column) lookups.
fn rows(csv: &str) -> Vec<std::collections::HashMap<String, f64>> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(k, v)| (k.to_string(), v.parse::<f64>().expect("number")))
                .collect()
        })
        .collect()
}

#[test]
fn bench_flies_the_path_and_reports_streaming_per_frame() {
    let dir = common::temp_path("world-bench");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("flight.csv");
    let (ok, out, err) = himal(&[
        "bench",
        "--scene",
        "world",
        "--path",
        "across",
        "--frames",
        "5",
        "--dt",
        "1.5",
        "--size",
        "96x54",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "bench failed:\n{out}\n{err}");
    for needle in [
        "himal bench --path across",
        "CPU plan + culling (ms)",
        "resident sectors",
        "pools: tiles",
        "frames over 2x the median",
    ] {
        assert!(out.contains(needle), "report lacks {needle:?}:\n{out}");
    }
    let rows = rows(&std::fs::read_to_string(&csv).unwrap());
    assert_eq!(rows.len(), 5, "one row per measured frame");
    // 1.5 s of the path (90 m at 60 m/s) per frame.
    let first = &rows[0];
    assert_eq!(first["t_s"], 0.0);
    assert_eq!(rows[4]["t_s"], 6.0);
    // The warm-up settled the start: every wanted sector resident.
    assert_eq!(first["missing_sectors"], 0.0, "{first:?}");
    assert!(first["resident_sectors"] > 100.0, "{first:?}");
    for r in &rows {
        assert!(r["tiles_used"] <= r["tiles_total"], "{r:?}");
        assert!(r["instances_live"] <= r["instances_total"], "{r:?}");
        assert!(
            r["terrain_triangles"] > 0.0,
            "the terrain draws every frame: {r:?}"
        );
        // The CSV rounds each column to 1e-4 ms.
        let sum = r["plan_ms"] + r["record_ms"] + r["submit_ms"];
        assert!((r["cpu_ms"] - sum).abs() < 1e-3, "{r:?}");
        assert!(r["stream_ms"] <= r["plan_ms"] + 1e-3, "{r:?}");
        // The phases are inside the streaming, the thread clock inside the wall
        // (it counts only the render thread's own CPU time).
        let phases = r["update_ms"] + r["tiles_ms"] + r["records_ms"] + r["follow_ms"];
        assert!(phases <= r["stream_ms"] + 1e-3, "{r:?}");
        assert!(
            r["thread_ms"] > 0.0 && r["thread_ms"] <= r["cpu_ms"] + 0.05,
            "{r:?}"
        );
        assert!(r["stream_thread_ms"] <= r["thread_ms"] + 1e-3, "{r:?}");
    }
    // Objects near the start are drawn (rocks, houses, trees at some level).
    assert!(first["object_triangles"] > 0.0, "{first:?}");
    let levels: f64 = (0..4).map(|l| first[&format!("lod{l}")]).sum();
    assert!(levels > 0.0, "{first:?}");
    // 360 m along, sectors behind fall out of the radius plus its 128 m
    // margin and new ones ahead come in, within the per-frame budget (4 MiB).
    assert!(rows[1..].iter().any(|r| r["evicted"] > 0.0), "{rows:?}");
    assert!(rows[1..].iter().any(|r| r["uploaded"] > 0.0), "{rows:?}");
    assert!(
        rows.iter()
            .all(|r| r["upload_bytes"] <= (4 << 20) as f64 + 64e3),
        "{rows:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_paths_and_scenes_without_paths_are_refused() {
    let r = himal(&[
        "bench", "--scene", "world", "--path", "nowhere", "--frames", "1", "--size", "16x16",
    ]);
    common::assert_fails_with(&["bench", "--path", "nowhere"], &r, "across");
    let r = himal(&[
        "bench", "--scene", "demo", "--path", "across", "--frames", "1", "--size", "16x16",
    ]);
    common::assert_fails_with(&["bench", "--scene", "demo"], &r, "no flight paths");
    // --csv writes pass rows without a path; --dt is the path's alone.
    let r = himal(&["bench", "--scene", "demo", "--dt", "0.1", "--size", "16x16"]);
    common::assert_fails_with(&["bench", "--dt"], &r, "need --path");
    let r = himal(&[
        "bench", "--scene", "world", "--path", "across", "--dolly", "1", "--size", "16x16",
    ]);
    common::assert_fails_with(&["bench", "--path", "--dolly"], &r, "choose one");
}
