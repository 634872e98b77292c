//! Anti-aliasing mode of a frame (`--aa`).

/// Which anti-aliasing runs after tone mapping.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AaMode {
    /// Tone mapping writes the output directly.
    #[default]
    None,
    /// A1 SMAA 1x: edges, blending weights, neighbourhood blending.
    Smaa,
}

impl AaMode {
    /// Every name `--aa` knows, implemented or not (issue #4).
    pub const NAMES: [&'static str; 6] = ["none", "smaa", "smaa-t2x", "tfq", "taa", "hraa"];

    /// Parses a mode name; the temporal modes are named but not built yet.
    pub fn parse(name: &str) -> Result<Self, String> {
        match name {
            "none" => Ok(Self::None),
            "smaa" => Ok(Self::Smaa),
            "smaa-t2x" | "tfq" | "taa" | "hraa" => Err(format!(
                "anti-aliasing mode \"{name}\" is not implemented yet (available: none, smaa)"
            )),
            other => Err(format!(
                "unknown anti-aliasing mode \"{other}\" (known: {})",
                Self::NAMES.join(", ")
            )),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Smaa => "smaa",
        }
    }
}
