//! Embeds every `.wgsl` file under `src/` so shaders are found by path
//! (`shaders/brdf.wgsl`, `passes/lighting/deferred.wgsl`) at run time.

use std::path::{Path, PathBuf};

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(path);
        }
    }
}

fn main() {
    // Read at run time: a build-script binary reused from another checkout
    // must not embed that checkout's (possibly deleted) shaders.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into());
    let src = Path::new(&manifest).join("src");
    println!("cargo:rerun-if-changed={}", src.display());
    let mut files = Vec::new();
    collect(&src, &mut files);
    files.sort();
    if files.is_empty() {
        panic!("no .wgsl files under {}", src.display());
    }
    let mut table = String::from("pub static SOURCES: &[(&str, &str)] = &[\n");
    for f in &files {
        let rel = f
            .strip_prefix(&src)
            .unwrap_or(f)
            .to_string_lossy()
            .replace('\\', "/");
        table += &format!(
            "    ({rel:?}, include_str!({:?})),\n",
            f.display().to_string()
        );
    }
    table += "];\n";
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap_or_default()).join("wgsl_sources.rs");
    if let Err(e) = std::fs::write(&out, table) {
        panic!("cannot write {}: {e}", out.display());
    }
}
