// shadows.cascade0..3, shadows.static, shadows.hero: depth of the casters seen
// from the sun (orthographic), one map per draw of this shader (TECHNIQUES S1, S2, S4).
// Bindings (shaders/shadow_caster.wgsl): shadow (light view-projection, time), objects, instances.
// Standard depth here (0 near .. 1 far, compare LessEqual), unlike the camera's reverse-Z.
// Vegetation (vs_vegetation / fs_vegetation) sways and alpha-tests as in the
// G-buffer, so grass casts blades, not cards; glTF MASK and BLEND materials
// are alpha-tested by depth_masked.wgsl.

#import scene
#import object_vertex
#import view
#import shadow_caster

@vertex
fn vs_main(@location(0) position: vec3f, @location(6) uv1: vec2f,
        @builtin(instance_index) instance: u32) -> @builtin(position) vec4f {
    let o = objects[instance_object(instances[instance])];
    // Trunks bend with their tree's bones (V2).
    return shadow.light_view_proj * object_world(o, false, position, vec2f(0.0), uv1, false, shadow.time.x);
}

struct VegetationOut {
    @builtin(position) clip: vec4f,
    @location(0) uv: vec2f,
    @location(1) @interpolate(flat) pattern: u32,
    // V3 impostors: p (centre-relative, units of R); flat the light's
    // direction w (tree space) and the layer (< 0: not an impostor)
    @location(2) impostor_p: vec3f,
    @location(3) @interpolate(flat) impostor_w: vec4f,
}

@vertex
fn vs_vegetation(
    @location(0) position: vec3f,
    @location(2) tangent: vec4f,
    @location(3) uv: vec2f,
    @location(6) uv1: vec2f,
    @builtin(instance_index) instance: u32,
) -> VegetationOut {
    let o = objects[instance_object(instances[instance])];
    var out: VegetationOut;
    var world = object_world(o, false, position, uv, uv1, true, shadow.time.x);
    world += grass_ripple(o, position, uv, world.xyz);
    out.clip = shadow.light_view_proj * world;
    out.uv = uv;
    out.pattern = foliage_pattern(o);
    out.impostor_p = vec3f(0.0);
    out.impostor_w = vec4f(0.0, 0.0, 1.0, -1.0);
    let layer = impostor_layer(uv1);
    if (layer >= 0) {
        // The impostor faces the light, so it casts its captured shape.
        let centre = (o.model * vec4f(position, 1.0)).xyz;
        let toward = impostor_toward_light(shadow.light_view_proj, centre);
        let g = impostor_object_vertex(o.normal_matrix, layer, position, tangent.w, uv, toward);
        out.clip = shadow.light_view_proj * impostor_world(o, g.local, false, shadow.time.x);
        out.impostor_p = g.p;
        out.impostor_w = vec4f(g.w, f32(layer));
    }
    return out;
}

@fragment
fn fs_vegetation(in: VegetationOut) {
    if (in.impostor_w.w >= 0.0) {
        if (impostor_pixel(i32(in.impostor_w.w), in.impostor_w.xyz, in.impostor_p).cover < 0.5) {
            discard;
        }
        return;
    }
    if (foliage_alpha(in.pattern, in.uv) < 0.5) {
        discard;
    }
}

// One tile of a map back to the far plane (its viewport): the world's static
// map renders a tile again in place (shadows.static.tileN).
@vertex
fn vs_clear(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    var c = fullscreen_clip(i);
    c.z = 1.0;
    return c;
}
