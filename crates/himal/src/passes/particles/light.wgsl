// particles.light (E4, Ryse "Particle Shading"): at the centre and the
// four corners of each particle's camera-facing quad (CORNERS; else at its
// centre only), the sun (its shadow from the static map, else its cascade, through a 4 x 4
// gather filter: R2) and every local light (a shadowed one through its
// atlas tile, the same gather) accumulated as illuminance and the
// intensity-weighted mean direction, into record PARTICLE_RECORDS slot + k
// (k = 0 the centre, 1 + i corner i). forward.particles interpolates
// the sums over the quad's four triangles around its centre and shades
// them with a per-pixel normal. One thread per (slot, point):
// workgroups x over the ring, y the emitter (its size at the particle's
// age places the corners). CPU twin: passes/particles/reference.rs
// `light_point`, `quad_point`.
#import particles
#import forward
#import shadow
#import view

override CORNERS: bool = true;

@group(0) @binding(0) var<uniform> lighting: Lighting;
@group(0) @binding(1) var<storage, read> particles: array<Particle>;
@group(0) @binding(2) var<storage, read> lights: LocalLights;
@group(0) @binding(3) var<storage, read> shadow_params: ShadowMaskParams;
@group(0) @binding(4) var cascades: texture_depth_2d_array;
@group(0) @binding(5) var static_map: texture_depth_2d_array;
@group(0) @binding(6) var shadow_sampler: sampler_comparison;
@group(0) @binding(7) var<storage, read_write> particle_light: array<ParticleLight>;
@group(0) @binding(8) var<uniform> view: View;
@group(0) @binding(9) var atlas: texture_depth_2d_array;
@group(0) @binding(10) var<storage, read> light_tiles: array<ShadowTile>;
@group(0) @binding(11) var<storage, read> emitters: array<ParticleEmitter>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let e = emitters[id.y];
    let per = select(1u, PARTICLE_RECORDS, CORNERS);
    let r = id.x / per;
    let k = id.x % per;
    if (r >= e.slots.y) {
        return;
    }
    let i = e.slots.x + r;
    let p = particles[i];
    var acc = ParticleLight(vec4f(0.0), vec4f(0.0));
    if (p.vel_alive.w > 0.5) {
        var x = p.pos_age.xyz;
        if (k > 0u) {
            x = particle_quad_point(view.view, x, particle_size(e, p.pos_age.w), particle_corner(k - 1u));
        }
        let dist = dot(x - view.camera_position.xyz, shadow_params.camera_forward.xyz);
        let vis = shadow_point_visibility(shadow_params, cascades, static_map, shadow_sampler, x, dist);
        acc = particle_light_add(acc, lighting.sun_illuminance.rgb * vis, lighting.sun_direction.xyz);
        acc.d.w = vis;
        for (var k = 0u; k < lights.count.x; k++) {
            let l = lights.lights[k];
            let li = local_light_illuminance(l, x);
            if (li.lit) {
                var v = 1.0;
                let tile = shadow_local_tile(l, x);
                if (u32(l.params.y) > 0u && tile >= 0) {
                    v = shadow_local_point_visibility(l, light_tiles[tile], x, atlas, shadow_sampler);
                }
                acc = particle_light_add(acc, li.e * v, li.dir);
            }
        }
    }
    particle_light[PARTICLE_RECORDS * i + k] = acc;
}
