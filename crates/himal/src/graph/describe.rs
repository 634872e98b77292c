//! Human-readable listing of a compiled graph (`himal render --graph`).

use std::fmt::Write as _;

use super::builder::{Resource, ResourceKind};
use super::compile::CompiledGraph;
use super::resource::ResourceUse;

fn shape(r: &Resource<'_>) -> String {
    match &r.kind {
        ResourceKind::Texture { desc, .. } => format!(
            "{}x{}x{} mips {} {:?}",
            desc.width, desc.height, desc.depth_or_layers, desc.mip_levels, desc.format
        ),
        ResourceKind::Buffer { desc, .. } => format!("buffer {} B", desc.size),
    }
}

impl CompiledGraph<'_> {
    /// Human-readable pass list, culled passes and resources with derived
    /// usages and pool slots (for `himal render --graph`).
    pub fn describe(&self) -> String {
        let width = self.passes.iter().map(|p| p.id.len()).max().unwrap_or(0);
        let mut s = String::new();
        let list = |uses: &[ResourceUse]| {
            uses.iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        };
        for (i, p) in self.passes.iter().enumerate() {
            let _ = write!(s, "{:>3}. {:<width$}", i + 1, p.id);
            if !p.reads.is_empty() {
                let _ = write!(s, "  reads {}", list(&p.reads));
            }
            if !p.writes.is_empty() {
                let _ = write!(s, "  writes {}", list(&p.writes));
            }
            if p.side_effect {
                s.push_str("  [side effect]");
            }
            s.push('\n');
        }
        if !self.culled.is_empty() {
            let _ = writeln!(s, "culled: {}", self.culled.join(", "));
        }
        s.push_str("resources:\n");
        let width = self
            .resources
            .iter()
            .map(|r| r.name.len())
            .max()
            .unwrap_or(0);
        let shapes: Vec<String> = self.resources.iter().map(shape).collect();
        let shape_width = shapes.iter().map(String::len).max().unwrap_or(0);
        for (i, (r, shape)) in self.resources.iter().zip(shapes).enumerate() {
            let origin = if r.is_imported() {
                "imported"
            } else {
                "transient"
            };
            let _ = write!(
                s,
                "  {:<width$}  {origin:<9}  {shape:<shape_width$}  usages {}",
                r.name, self.usages[i]
            );
            if let Some(slot) = self.slot_of[i] {
                let kind = match r.kind {
                    ResourceKind::Texture { .. } => "texture",
                    ResourceKind::Buffer { .. } => "buffer",
                };
                let _ = write!(s, "  pool {kind} slot {slot}");
            }
            if r.output {
                s.push_str("  [output]");
            }
            s.push('\n');
        }
        s
    }
}
