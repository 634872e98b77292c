//! Models built into the library (`file = "builtin:NAME"` in a scene's
//! `[[gltf]]`): the demo's assets, so it renders from anywhere without
//! files beside the program. Sources and licences: `assets/`.

/// The prefix that names a built-in model instead of a file.
pub const PREFIX: &str = "builtin:";

/// (name, GLB bytes).
const MODELS: [(&str, &[u8]); 2] = [
    (
        "DamagedHelmet.glb",
        include_bytes!("../../../../assets/DamagedHelmet/DamagedHelmet.glb"),
    ),
    // The walking character (skinned, three clips).
    ("Fox.glb", include_bytes!("../../../../assets/Fox/Fox.glb")),
];

/// The bytes of built-in model `name` (without the prefix).
pub fn model(name: &str) -> Option<&'static [u8]> {
    MODELS.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}

/// The built-in models' names, for messages.
pub fn names() -> Vec<&'static str> {
    MODELS.iter().map(|(n, _)| *n).collect()
}
