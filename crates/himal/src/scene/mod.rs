//! Scene description: meshes, materials, cameras, TOML scene files, procedural demo world.
