// Aerial perspective of a surface at distance `dist` seen along -v (the
// deferred lighting's fog, shared with forward.blend): the caller applies
// c T + L_in (1 - T) with (L_in, T) the result's (rgb, a).
// T = exp(-fog.x dist); L_in = fog.y x the Preetham sky radiance toward -v
// (`preetham`, the caller's sample) or, fog.z = 1 (Bruneton sky, L1), the
// SH sky radiance toward the horizon-clamped -v, so distant terrain fades to
// the colour of the sky drawn behind it. `fog` is Lighting's.
// CPU twin: passes/lighting/reference.rs `aerial_perspective`.
#import sh

fn aerial_perspective(dist: f32, v: vec3f, fog: vec4f, sky_irradiance: Sh9, preetham: vec3f) -> vec4f {
    let transmittance = exp(-fog.x * dist);
    var inscatter = preetham * fog.y;
    if (fog.z > 0.5) {
        let d = normalize(vec3f(-v.x, max(-v.y, 0.0), -v.z) + vec3f(0.0, 1e-4, 0.0));
        inscatter = max(sh9_eval_radiance_from_irradiance(sky_irradiance, d), vec3f(0.0)) * fog.y;
    }
    return vec4f(inscatter, transmittance);
}
