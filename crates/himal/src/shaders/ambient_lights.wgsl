// Ryse's ambient lights (SIGGRAPH 2014, docs/ambient-lights.md): volumes
// (boxes yawed about +Y, or spheres) inside which the ambient light, sky
// diffuse and ambient specular alike, is multiplied by an RGB factor, faded
// (smoothstep) back to 1 over the outer `falloff` fraction of the volume;
// overlapping volumes multiply. Like gltf_material, this module brings its
// binding: every shader that imports it binds `ambient_lights` (the scene's
// lights, passes/lighting/ambient.rs; count 0 when off).
// CPU twin: passes/lighting/reference.rs `ambient_light_scale`, `ambient_scale`.

const MAX_AMBIENT_LIGHTS: u32 = 64u;

struct AmbientLight {
    // xyz: centre (m); w: 0 = box, 1 = sphere
    position_shape: vec4f,
    // xyz: box half-extents or (radius, -, -); w: falloff fraction
    extent_falloff: vec4f,
    // rgb: factor
    factor: vec4f,
    // x: cos(yaw), y: sin(yaw)
    yaw: vec4f,
}

struct AmbientLights {
    // x: how many lights are in use
    count: vec4u,
    lights: array<AmbientLight, MAX_AMBIENT_LIGHTS>,
}

@group(0) @binding(20) var<storage, read> ambient_lights: AmbientLights;

// The multiplier of one light at world position p.
fn ambient_light_scale(l: AmbientLight, p: vec3f) -> vec3f {
    let d = p - l.position_shape.xyz;
    var r: f32;
    if (l.position_shape.w > 0.5) {
        r = length(d) / l.extent_falloff.x;
    } else {
        // Into the box's frame: the inverse of the yaw rotation about +Y.
        let c = l.yaw.x;
        let s = l.yaw.y;
        let q = abs(vec3f(c * d.x - s * d.z, d.y, s * d.x + c * d.z)) / l.extent_falloff.xyz;
        r = max(q.x, max(q.y, q.z));
    }
    let f = l.extent_falloff.w;
    var t = select(0.0, 1.0, r <= 1.0);
    if (f > 0.0) {
        t = saturate((1.0 - r) / f);
    }
    let w = t * t * (3.0 - 2.0 * t);
    return mix(vec3f(1.0), l.factor.rgb, w);
}

// The product of every light's multiplier at p.
fn ambient_scale(p: vec3f) -> vec3f {
    var s = vec3f(1.0);
    for (var k = 0u; k < min(ambient_lights.count.x, MAX_AMBIENT_LIGHTS); k++) {
        s *= ambient_light_scale(ambient_lights.lights[k], p);
    }
    return s;
}
