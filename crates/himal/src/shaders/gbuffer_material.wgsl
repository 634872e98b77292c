// The G-buffer material target's channels (Rgba8Unorm): glossiness,
// reflectance, metallic|foliage, anisotropy. The blue channel's 256 codes
// are split (V5): codes 0..127 are metallic c / 127 (0 and 1 exact),
// codes 128..255 mark a foliage pixel (grass, bush and leaf cards, impostor
// leaves) with leaf amount (c - 128) / 127 and metallic 0: leaves are
// dielectrics, so the two never meet. CPU twin: passes/gbuffer/mod.rs
// `encode_metallic_foliage`, `decode_metallic_foliage`; docs/techniques/V5.md.

// The stored value (code / 255) of `metallic` or, when `foliage` > 0, of the leaf amount.
fn gbuffer_metallic_foliage(metallic: f32, foliage: f32) -> f32 {
    if (foliage > 0.0) {
        return (128.0 + round(127.0 * saturate(foliage))) / 255.0;
    }
    return round(127.0 * saturate(metallic)) / 255.0;
}

fn gbuffer_material_code(z: f32) -> f32 {
    return round(saturate(z) * 255.0);
}

// Metallic of a stored blue channel (0 on foliage).
fn gbuffer_metallic(z: f32) -> f32 {
    let c = gbuffer_material_code(z);
    return select(c / 127.0, 0.0, c > 127.5);
}

// Leaf amount of a stored blue channel (0 off foliage).
fn gbuffer_foliage(z: f32) -> f32 {
    return max(gbuffer_material_code(z) - 128.0, 0.0) / 127.0;
}
