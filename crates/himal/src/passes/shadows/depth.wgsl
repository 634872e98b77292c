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
fn vs_main(@location(0) position: vec3f, @builtin(instance_index) instance: u32) -> @builtin(position) vec4f {
    let o = objects[instance_object(instances[instance])];
    return shadow.light_view_proj * object_world(o, o.model, position, vec2f(0.0), false, 0.0);
}

struct VegetationOut {
    @builtin(position) clip: vec4f,
    @location(0) uv: vec2f,
    @location(1) @interpolate(flat) pattern: u32,
}

@vertex
fn vs_vegetation(
    @location(0) position: vec3f,
    @location(3) uv: vec2f,
    @builtin(instance_index) instance: u32,
) -> VegetationOut {
    let o = objects[instance_object(instances[instance])];
    var out: VegetationOut;
    out.clip = shadow.light_view_proj * object_world(o, o.model, position, uv, true, shadow.time.x);
    out.uv = uv;
    out.pattern = foliage_pattern(o);
    return out;
}

@fragment
fn fs_vegetation(in: VegetationOut) {
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
