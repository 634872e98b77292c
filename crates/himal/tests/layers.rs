//! The layers of docs/architecture.md: lower layers never import higher
//! ones. A file that breaks the rule fails here with its path and line.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("source folder") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// Lines under `src/<layer>` that name any of `higher` (`crate::frame`, ...).
fn violations(layer: &str, higher: &[&str]) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    let dir = root.join(layer);
    if dir.is_dir() {
        rust_files(&dir, &mut files);
    } else {
        files.push(root.join(format!("{layer}.rs")));
    }
    let mut found = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).expect("readable source");
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for h in higher {
                let module = format!("crate::{h}");
                let hit = code.match_indices(&module).any(|(at, _)| {
                    let rest = &code[at + module.len()..];
                    !rest.starts_with(|c: char| c.is_alphanumeric() || c == '_')
                });
                if hit {
                    let rel = f.strip_prefix(&root).unwrap_or(&f).display();
                    found.push(format!("src/{rel}:{}: {}", i + 1, line.trim()));
                }
            }
        }
    }
    found
}

#[test]
fn passes_do_not_import_the_frame_or_the_renderer() {
    let v = violations("passes", &["frame", "renderer", "settings", "present"]);
    assert!(
        v.is_empty(),
        "passes/ imports a higher layer:\n{}",
        v.join("\n")
    );
}

#[test]
fn the_graph_and_the_gpu_scene_sit_below_the_passes() {
    let above = ["passes", "frame", "renderer", "settings", "present"];
    for layer in ["graph", "gpu_scene", "gpu", "shader", "math"] {
        let mut higher: Vec<&str> = above.to_vec();
        if matches!(layer, "gpu" | "shader" | "math") {
            higher.extend(["graph", "gpu_scene"]);
        }
        let v = violations(layer, &higher);
        assert!(
            v.is_empty(),
            "{layer}/ imports a higher layer:\n{}",
            v.join("\n")
        );
    }
}

#[test]
fn the_frame_does_not_import_the_renderer() {
    let v = violations("frame", &["renderer"]);
    assert!(
        v.is_empty(),
        "frame.rs imports the renderer:\n{}",
        v.join("\n")
    );
}
