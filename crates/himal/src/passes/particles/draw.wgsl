// forward.particles (E4): camera-facing quads of the live particles, after
// the deferred lighting and the forward surfaces, premultiplied over the
// HDR target (One, OneMinusSrcAlpha), their coverage into a reactive mask
// for the TAA. One instance per slot (dead slots
// give a degenerate quad); a quad is four triangles around its centre.
// Shading: the light particles.light accumulated at the centre and the
// corners, interpolated across the triangles (Ryse's per vertex, after
// Persson; CORNERS off: the centre's alone; PER_PIXEL: the same sums at
// each pixel, the reference) with the sprite's per-pixel normal (the
// disc's hemisphere, or a normal-mapped sprite: the built-in puff or a
// scene's image, turned by a per-particle angle), plus the world's diffuse
// ambient (or the environment cube's lowest specular mip used as diffuse,
// Ryse); no constant ambient. Soft particles: alpha fades over
// SOFT_DISTANCE in front of the scene depth. DEBUG (--view
// particle-lighting): white particles. CASCADED_SHADOWS: per-pixel light
// with the world's sun shadow (cascades, Poisson filter: shadows.mask's
// lookup), the reference of the static-map shadow. CPU twin of the shading:
// passes/particles/reference.rs `light_diffuse`, `sprite_normal`,
// `sprite_normal_mapped`, `sprite_rotate`.
#import particles
#import forward
#import shadow
#import view
#import sh
#import ambient_lights

override PER_PIXEL: bool = false;
override CORNERS: bool = true;
override DEBUG: bool = false;
override PROBE_AMBIENT: bool = false;
override CASCADED_SHADOWS: bool = false;

// Fade distance of soft particles (m).
const SOFT_DISTANCE: f32 = 0.5;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> particles: array<Particle>;
@group(0) @binding(2) var<storage, read> emitters: array<ParticleEmitter>;
@group(0) @binding(3) var<storage, read> particle_light: array<ParticleLight>;
@group(0) @binding(4) var depth: texture_depth_2d;
@group(0) @binding(5) var env_specular: texture_cube<f32>;
@group(0) @binding(6) var env_sampler: sampler;
@group(0) @binding(7) var<uniform> lighting: Lighting;
@group(0) @binding(8) var<storage, read> lights: LocalLights;
@group(0) @binding(9) var<storage, read> shadow_params: ShadowMaskParams;
@group(0) @binding(10) var cascades: texture_depth_2d_array;
@group(0) @binding(11) var static_map: texture_depth_2d_array;
@group(0) @binding(12) var shadow_sampler: sampler_comparison;
// particles.sort: the slot drawn at each instance (far to near per emitter).
@group(0) @binding(13) var<storage, read> order: array<u32>;
// Normal-mapped sprites: rgb the tangent-space normal (n/2 + 1/2), a the
// opacity; layer 0 the built-in puff (passes/particles/sprite.rs).
@group(0) @binding(14) var sprites: texture_2d_array<f32>;
@group(0) @binding(15) var sprite_sampler: sampler;

struct ParticleOut {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
    // the quad's corner in [-1, 1]^2
    @location(1) corner: vec2f,
    @location(2) color: vec4f,
    // particles.light's sums at this vertex, interpolated
    @location(3) light_e: vec4f,
    @location(4) light_d: vec4f,
    // x: sprite layer (-1 the disc), yz: the sprite's angle (cos, sin)
    @location(5) @interpolate(flat) sprite: vec4f,
}

@vertex
fn vs_main(@builtin(vertex_index) v: u32, @builtin(instance_index) instance: u32) -> ParticleOut {
    var out: ParticleOut;
    let slot = order[instance];
    let p = particles[slot];
    if (p.vel_alive.w < 0.5) {
        out.clip = vec4f(2.0, 2.0, 2.0, 1.0);
        return out;
    }
    var ei = 0u;
    for (var k = 0u; k < arrayLength(&emitters); k++) {
        if (slot >= emitters[k].slots.x) {
            ei = k;
        }
    }
    let e = emitters[ei];
    // Triangle t = v / 3 joins the centre (record 0) and corners t, t + 1
    // (records 1 + corner).
    let t = v / 3u;
    let j = v % 3u;
    var c = vec2f(0.0);
    var k = 0u;
    if (j > 0u) {
        let corner = (t + j - 1u) % 4u;
        c = particle_corner(corner);
        k = 1u + corner;
    }
    out.world = particle_quad_point(view.view, p.pos_age.xyz, particle_size(e, p.pos_age.w), c);
    let l = particle_light[PARTICLE_RECORDS * slot + select(0u, k, CORNERS)];
    out.light_e = l.e;
    out.light_d = l.d;
    out.clip = view.view_proj * vec4f(out.world, 1.0);
    out.corner = c;
    out.color = particle_color(e, p.pos_age.w);
    out.sprite = vec4f(e.size.z, particle_sprite_angle(slot), 0.0);
    return out;
}

// The per-pixel reference: particles.light's sums at this point.
fn light_at(x: vec3f) -> ParticleLight {
    var acc = ParticleLight(vec4f(0.0), vec4f(0.0));
    let dist = dot(x - view.camera_position.xyz, shadow_params.camera_forward.xyz);
    var vis = 0.0;
    if (CASCADED_SHADOWS) {
        vis = shadow_world_visibility(shadow_params, cascades, static_map, shadow_sampler, x, vec3f(0.0), dist);
    } else {
        vis = shadow_point_visibility(shadow_params, cascades, static_map, shadow_sampler, x, dist);
    }
    acc = particle_light_add(acc, lighting.sun_illuminance.rgb * vis, lighting.sun_direction.xyz);
    for (var k = 0u; k < lights.count.x; k++) {
        let li = local_light_illuminance(lights.lights[k], x);
        if (li.lit) {
            acc = particle_light_add(acc, li.e, li.dir);
        }
    }
    return acc;
}

struct DrawOut {
    @location(0) color: vec4f,
    // Coverage for the TAA's reactive mask (R8, blended like the colour:
    // 1 − Π(1 − a)).
    @location(1) reactive: vec4f,
}

@fragment
fn fs_main(in: ParticleOut) -> DrawOut {
    let layer = i32(in.sprite.x);
    let rot = in.sprite.yz;
    let q = particle_sprite_rotate(in.corner, rot);
    // Sampled before any discard: implicit derivatives need uniform control flow.
    let texel = textureSample(sprites, sprite_sampler, vec2f(0.5 + 0.5 * q.x, 0.5 - 0.5 * q.y), max(layer, 0));
    let r2 = dot(in.corner, in.corner);
    var coverage = 1.0 - r2;
    var n = vec3f(0.0);
    if (layer < 0) {
        if (r2 >= 1.0) {
            discard;
        }
        n = particle_sprite_normal(view.view, in.corner, r2);
    } else {
        coverage = texel.a;
        n = particle_sprite_normal_mapped(view.view, texel.rgb * 2.0 - 1.0, rot);
    }
    // Soft particles: the scene's view distance behind this fragment.
    let scene_depth = textureLoad(depth, vec2i(in.clip.xy), 0);
    var fade = 1.0;
    if (scene_depth > 0.0) {
        let behind = view_distance(view, scene_depth) - view_distance(view, in.clip.z);
        fade = saturate(behind / SOFT_DISTANCE);
    }
    let alpha = in.color.a * coverage * fade;
    if (alpha <= 0.0) {
        discard;
    }
    var acc = ParticleLight(in.light_e, in.light_d);
    if (PER_PIXEL || CASCADED_SHADOWS) {
        acc = light_at(in.world);
    }
    var ambient = max(sh9_eval(lighting.sky_irradiance, n), vec3f(0.0)) / PI;
    if (PROBE_AMBIENT) {
        let lowest = f32(textureNumLevels(env_specular) - 1u);
        ambient = textureSampleLevel(env_specular, env_sampler, n, lowest).rgb;
    }
    ambient *= ambient_scale(in.world);
    var albedo = in.color.rgb;
    if (DEBUG) {
        albedo = vec3f(1.0);
    }
    let c = albedo * (particle_light_diffuse(acc, n) + ambient);
    return DrawOut(vec4f(c * alpha, alpha), vec4f(alpha, 0.0, 0.0, alpha));
}
