//! The malformed-input corpus (issue #16): several hundred hostile scene
//! files, glTF/GLB files, height maps, environment maps and arguments,
//! written by `tests/corpus/generate.py`. Every case must end with a
//! non-zero exit, no panic, no signal, no hang, and a message that names
//! the input. `HIMAL_CORPUS=name,name` runs only those cases.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Longest a case may run. The slowest legitimate case (a valid input that
/// only fails after the GPU starts) takes about 3 s on lavapipe with a
/// warm pipeline cache; a case still running after this has hung.
const HANG: Duration = Duration::from_secs(120);

struct Case {
    class: String,
    name: String,
    needle: String,
    args: Vec<String>,
}

struct Outcome {
    code: Option<i32>,
    stderr: String,
    elapsed: Duration,
    hung: bool,
}

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

/// Runs the generator into `dir` and returns the manifest it wrote.
fn generate(dir: &Path) -> String {
    let status = Command::new("python3")
        .arg(corpus_dir().join("generate.py"))
        .arg(dir)
        .stdout(Stdio::null())
        .status()
        .expect("python3 runs the corpus generator");
    assert!(status.success(), "generate.py failed");
    std::fs::read_to_string(dir.join("cases.tsv")).expect("manifest")
}

fn parse(manifest: &str, corpus: &Path) -> Vec<Case> {
    let corpus = corpus.to_string_lossy();
    manifest
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            assert!(f.len() >= 4 && f[2] == "error", "bad manifest line {l}");
            Case {
                class: f[0].into(),
                name: f[1].into(),
                needle: f[3].replace("{corpus}", &corpus),
                args: f[4..]
                    .iter()
                    .map(|a| a.replace("{corpus}", &corpus))
                    .collect(),
            }
        })
        .collect()
}

fn run_case(case: &Case, out: &Path, cache: &Path) -> Outcome {
    let out_s = out.to_string_lossy();
    std::fs::create_dir_all(out).expect("case folder");
    let args: Vec<String> = case
        .args
        .iter()
        .map(|a| a.replace("{out}", &out_s))
        .collect();
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_himal"))
        .args(&args)
        .current_dir(out)
        .env("HIMAL_CACHE_DIR", cache)
        .env("RUST_BACKTRACE", "0")
        // lavapipe probes Wayland and complains without one.
        .env("XDG_RUNTIME_DIR", out)
        .env_remove("HIMAL_MEMORY_BUDGET")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("himal starts");
    // stderr is read on a thread so a chatty case cannot block on a full pipe.
    let mut pipe = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        std::io::Read::read_to_end(&mut pipe, &mut s).ok();
        String::from_utf8_lossy(&s).into_owned()
    });
    let mut hung = false;
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > HANG {
            hung = true;
            child.kill().ok();
            break child.wait().expect("wait after kill");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    Outcome {
        code: status.code(),
        stderr: reader.join().unwrap_or_default(),
        elapsed: start.elapsed(),
        hung,
    }
}

/// Why the outcome breaks the rule, if it does.
fn verdict(case: &Case, o: &Outcome, out: &Path) -> Option<String> {
    let needle = case.needle.replace("{out}", &out.to_string_lossy());
    if o.hung {
        Some(format!("hung (killed after {} s)", HANG.as_secs()))
    } else if o.code.is_none() {
        Some("killed by a signal".into())
    } else if o.code == Some(101) || o.stderr.contains("panicked") {
        Some("panicked".into())
    } else if o.code == Some(0) {
        Some("exit 0: the input was accepted".into())
    } else if !o.stderr.contains(&needle) {
        Some(format!("the message does not name \"{needle}\""))
    } else {
        None
    }
}

#[test]
fn every_malformed_input_is_a_clear_error() {
    let root = common::temp_path("corpus");
    std::fs::remove_dir_all(&root).ok();
    let manifest = generate(&root);
    // The committed manifest is the list reviewers see: it must be current.
    let committed = std::fs::read_to_string(corpus_dir().join("cases.tsv")).expect("cases.tsv");
    assert_eq!(
        committed, manifest,
        "tests/corpus/cases.tsv is stale: run tests/corpus/generate.py"
    );
    let only: Option<Vec<String>> = std::env::var("HIMAL_CORPUS")
        .ok()
        .map(|s| s.split(',').map(str::to_string).collect());
    let cases: Vec<Case> = parse(&manifest, &root)
        .into_iter()
        .filter(|c| only.as_ref().is_none_or(|o| o.contains(&c.name)))
        .collect();
    let cache = root.join("cache");
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, Outcome)>> = Mutex::new(Vec::new());
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get().min(4));
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = cases.get(i) else { break };
                    let out = root
                        .join("out")
                        .join(format!("{}-{}", case.class, case.name));
                    let o = run_case(case, &out, &cache);
                    results.lock().expect("results").push((i, o));
                }
            });
        }
    });
    let mut results = results.into_inner().expect("results");
    results.sort_by_key(|(i, _)| *i);
    let mut by_class: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    let mut failures = Vec::new();
    let mut slowest = (Duration::ZERO, "");
    for (i, o) in &results {
        let case = &cases[*i];
        let out = root
            .join("out")
            .join(format!("{}-{}", case.class, case.name));
        let entry = by_class.entry(&case.class).or_default();
        entry.0 += 1;
        if o.elapsed > slowest.0 {
            slowest = (o.elapsed, &case.name);
        }
        if let Some(why) = verdict(case, o, &out) {
            entry.1 += 1;
            let last: String = o
                .stderr
                .lines()
                .rev()
                .take(3)
                .collect::<Vec<_>>()
                .join(" | ");
            failures.push(format!(
                "{}/{}: {why}; stderr: {last}",
                case.class, case.name
            ));
        }
    }
    for (class, (n, bad)) in &by_class {
        println!("corpus {class}: {n} cases, {bad} failing");
    }
    println!(
        "slowest case: {} ({:.1} s)",
        slowest.1,
        slowest.0.as_secs_f64()
    );
    std::fs::remove_dir_all(&root).ok();
    assert!(
        failures.is_empty(),
        "{} of {} cases break the rule:\n{}",
        failures.len(),
        results.len(),
        failures.join("\n")
    );
}
