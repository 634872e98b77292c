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

/// Loads glTF `path` (variant `variant`, charged to `budget`): the built-in
/// model a `builtin:NAME` path names, else the file. The one place both
/// `--gltf` and `[[gltf]]` entries read a model.
pub(crate) fn load_gltf(
    path: &std::path::Path,
    budget: crate::budget::MemoryBudget,
    variant: Option<&str>,
) -> Result<super::gltf::GltfAsset, super::SceneError> {
    match path.to_str().and_then(|p| p.strip_prefix(PREFIX)) {
        Some(name) => {
            let bytes = model(name).ok_or_else(|| super::SceneError::Invalid {
                file: path.display().to_string(),
                message: format!("no such built-in model (built in: {})", names().join(", ")),
            })?;
            super::gltf::load_from_bytes_with(path, bytes, budget, variant)
        }
        None => super::gltf::load_with(path, budget, variant),
    }
}
