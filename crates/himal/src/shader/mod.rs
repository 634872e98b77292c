//! WGSL composition: shared modules in `src/shaders/` are imported with a
//! line `#import name`; each module is included once, imports first. A line
//! map turns naga's error positions back into the file and line written.
//!
//! Every `.wgsl` under `src/` is embedded at build time (see `build.rs`).

mod reflect;

use std::collections::HashSet;

pub use reflect::{BindingInfo, ReflectedLayout};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/wgsl_sources.rs"));
}

/// Composition, parse, validation and reflection failures, located in the
/// file and line that was written (not the composed text).
#[derive(thiserror::Error, Debug)]
pub enum ShaderError {
    /// No embedded shader has this path.
    #[error("unknown shader \"{0}\"")]
    Unknown(String),
    /// An `#import` names a module that is not in `src/shaders/`.
    #[error("{file}:{line}: unknown module \"{module}\" in #import")]
    UnknownImport {
        /// File holding the `#import` line.
        file: String,
        /// 1-based line of the `#import` in that file.
        line: usize,
        /// The module name imported.
        module: String,
    },
    /// A module imports itself through a chain of imports.
    #[error("{file}: import cycle through \"{module}\"")]
    Cycle {
        /// File whose import closes the cycle.
        file: String,
        /// The module imported again.
        module: String,
    },
    /// naga could not parse the composed WGSL.
    #[error("{file}:{line}: {message}")]
    Parse {
        /// File the failing line came from.
        file: String,
        /// 1-based line in that file.
        line: usize,
        /// naga's message.
        message: String,
    },
    /// naga parsed the shader but validation (types, uniformity, limits) failed.
    #[error("{shader}: validation failed at {file}:{line}: {message}")]
    Validation {
        /// Name of the composed shader.
        shader: String,
        /// File the failing line came from.
        file: String,
        /// 1-based line in that file.
        line: usize,
        /// naga's message.
        message: String,
    },
    /// A global binding has a type the layout reflection does not map to wgpu.
    #[error("{shader}: {message}")]
    Reflection {
        /// Name of the composed shader.
        shader: String,
        /// What could not be reflected.
        message: String,
    },
}

/// Every embedded WGSL file as (path relative to `src/`, text).
pub fn sources() -> &'static [(&'static str, &'static str)] {
    embedded::SOURCES
}

/// Text of an embedded WGSL file (`passes/lighting/deferred.wgsl`).
pub fn source(path: &str) -> Option<&'static str> {
    embedded::SOURCES
        .iter()
        .find(|(p, _)| *p == path)
        .map(|(_, s)| *s)
}

/// A composed, parsed and validated shader.
pub struct ComposedShader {
    /// Name it was composed under: the embedded path or the name given to [`compose_str`].
    pub name: String,
    /// The composed WGSL text, imported modules first.
    pub source: String,
    /// For each line of `source`: (file, 1-based line in that file).
    pub line_map: Vec<(String, usize)>,
    /// The parsed module.
    pub module: naga::Module,
    /// naga's validation results for [`Self::module`].
    pub info: naga::valid::ModuleInfo,
}

impl ComposedShader {
    /// Where line `line` (1-based) of the composed text came from.
    pub fn origin(&self, line: usize) -> (String, usize) {
        self.line_map
            .get(line.saturating_sub(1))
            .cloned()
            .unwrap_or_else(|| (self.name.clone(), line))
    }

    /// Bind-group layouts derived from the module's global bindings.
    pub fn layout(&self) -> Result<ReflectedLayout, ShaderError> {
        reflect::reflect(self)
    }

    /// The composed text, for `wgpu::ShaderSource::Wgsl`.
    pub fn wgsl(&self) -> std::borrow::Cow<'_, str> {
        std::borrow::Cow::Borrowed(&self.source)
    }
}

/// Composes an embedded shader by path.
pub fn compose(path: &str) -> Result<ComposedShader, ShaderError> {
    let text = source(path).ok_or_else(|| ShaderError::Unknown(path.to_string()))?;
    compose_str(path, text)
}

/// Composes WGSL text (which may `#import` embedded modules).
pub fn compose_str(name: &str, text: &str) -> Result<ComposedShader, ShaderError> {
    let mut out = Composer {
        source: String::new(),
        line_map: Vec::new(),
        done: HashSet::new(),
    };
    out.add(name, text, &mut Vec::new())?;
    let Composer {
        source, line_map, ..
    } = out;
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| {
        let line = e
            .location(&source)
            .map(|l| l.line_number as usize)
            .unwrap_or(0);
        let (file, line) = map_line(&line_map, name, line);
        ShaderError::Parse {
            file,
            line,
            message: e.message().to_string(),
        }
    })?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| {
        let line = e
            .location(&source)
            .map(|l| l.line_number as usize)
            .unwrap_or(0);
        let (file, line) = map_line(&line_map, name, line);
        let message = e.as_inner().to_string();
        ShaderError::Validation {
            shader: name.to_string(),
            file,
            line,
            message,
        }
    })?;
    Ok(ComposedShader {
        name: name.to_string(),
        source,
        line_map,
        module,
        info,
    })
}

fn map_line(map: &[(String, usize)], name: &str, line: usize) -> (String, usize) {
    map.get(line.saturating_sub(1))
        .cloned()
        .unwrap_or_else(|| (name.to_string(), line))
}

struct Composer {
    source: String,
    line_map: Vec<(String, usize)>,
    done: HashSet<String>,
}

impl Composer {
    fn add(&mut self, file: &str, text: &str, stack: &mut Vec<String>) -> Result<(), ShaderError> {
        stack.push(file.to_string());
        let mut body = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let Some(rest) = line.trim_start().strip_prefix("#import") else {
                body.push((i + 1, line));
                continue;
            };
            let module = rest.trim().trim_end_matches(';').trim();
            let path = format!("shaders/{module}.wgsl");
            if stack.contains(&path) {
                return Err(ShaderError::Cycle {
                    file: file.into(),
                    module: module.into(),
                });
            }
            if self.done.contains(&path) {
                continue;
            }
            let text = source(&path).ok_or_else(|| ShaderError::UnknownImport {
                file: file.into(),
                line: i + 1,
                module: module.into(),
            })?;
            self.add(&path, text, stack)?;
            self.done.insert(path);
            // Keep line numbers of the importing file intact.
            body.push((i + 1, ""));
        }
        for (n, line) in body {
            self.source.push_str(line);
            self.source.push('\n');
            self.line_map.push((file.to_string(), n));
        }
        stack.pop();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Modules that call functions their importer defines, each with the
    /// module that supplies them in the frame (validated in its place).
    /// (object_vertex reads the importer's `objects` for V2's tree bones,
    /// ripple its `ripple` grid.)
    const IMPORTER_DEFINED: [(&str, &str); 4] = [
        ("shaders/ripple.wgsl", "passes/gbuffer/gbuffer.wgsl"),
        ("shaders/impostor_draw.wgsl", "shaders/impostor_atlas.wgsl"),
        ("shaders/object_vertex.wgsl", "passes/gbuffer/gbuffer.wgsl"),
        ("shaders/forward_vertex.wgsl", "passes/forward/forward.wgsl"),
    ];

    /// Every embedded shader composes and validates; modules are validated
    /// on their own too (they contain no entry points), except those in
    /// [`IMPORTER_DEFINED`], validated through their supplier.
    #[test]
    fn every_shader_composes_and_validates() {
        let mut failures = Vec::new();
        for (path, _) in sources() {
            let supplied = IMPORTER_DEFINED.iter().find(|(m, _)| m == path);
            if let Some((_, supplier)) = supplied {
                assert!(
                    sources().iter().any(|(p, _)| p == supplier),
                    "{supplier}, which supplies {path}, is not embedded"
                );
                continue;
            }
            if let Err(e) = compose(path) {
                failures.push(e.to_string());
            }
        }
        assert!(
            failures.is_empty(),
            "shader errors:\n{}",
            failures.join("\n")
        );
    }

    #[test]
    fn errors_point_at_the_written_file_and_line() {
        let text = "#import color\n\nfn broken() -> f32 {\n  return nope;\n}\n";
        let Err(err) = compose_str("test/broken.wgsl", text) else {
            panic!("expected an error")
        };
        let msg = err.to_string();
        assert!(msg.contains("test/broken.wgsl:4"), "{msg}");
    }

    #[test]
    fn unknown_import_names_file_and_line() {
        let Err(err) = compose_str("x.wgsl", "\n#import nosuchmodule\n") else {
            panic!("expected an error")
        };
        assert_eq!(
            err.to_string(),
            "x.wgsl:2: unknown module \"nosuchmodule\" in #import"
        );
    }

    #[test]
    fn modules_are_included_once() {
        let text =
            "#import color\n#import color\nfn f() -> f32 { return luminance(vec3f(1.0)); }\n";
        let shader = compose_str("t.wgsl", text).expect("composes");
        assert_eq!(shader.source.matches("fn luminance").count(), 1);
    }
}
