// V5 leaf shading (docs/techniques/V5.md "Leaf shading"; CPU twin
// passes/lighting/reference.rs `leaf_translucency`, `leaf_material`).
// After Sousa, "Vegetation Procedural Animation and Shading in Crysis" (GPU
// Gems 3 ch. 16): light through the leaf from behind, tinted by its albedo,
// partly view dependent; a low, broad dielectric specular. `f` is the
// pixel's leaf amount (shaders/gbuffer_material.wgsl): 1 on cards, the leaf
// fraction on impostors, 0 elsewhere.
#import math

// Transmitted over reflected diffuse light (a leaf's thickness).
const LEAF_TRANSLUCENCY: f32 = 0.6;
// Share of the view-dependent term (CryEngine's "back view dependency").
const LEAF_BACK_VIEW: f32 = 0.5;
// Waxy cuticle: F0 of a dielectric of index ~1.42, and glossiness at most 0.3.
const LEAF_F0: f32 = 0.03;
const LEAF_GLOSS_MAX: f32 = 0.3;

// The leaf's (glossiness, reflectance), blended by f.
fn leaf_material(glossiness: f32, reflectance: f32, f: f32) -> vec2f {
    return vec2f(mix(glossiness, min(glossiness, LEAF_GLOSS_MAX), f), mix(reflectance, LEAF_F0, f));
}

// Radiance toward v per unit illuminance from l (1/sr) transmitted through
// the leaf: k f albedo / pi ((1 - d) max(-n.l, 0) + d saturate(-v.l)^4).
fn leaf_translucency(diffuse_albedo: vec3f, f: f32, n: vec3f, v: vec3f, l: vec3f) -> vec3f {
    let back = max(-dot(n, l), 0.0);
    // The view-dependent lobe around the light's direction (power 4).
    let t = saturate(-dot(v, l));
    let through = (t * t) * (t * t);
    let b = mix(back, through, LEAF_BACK_VIEW);
    return diffuse_albedo * (f * LEAF_TRANSLUCENCY * b / PI);
}
