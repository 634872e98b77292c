// V2 wind field (docs/techniques/V2.md; CPU twin scene/wind.rs `WindGpu::at`):
// the global wind with travelling gusts plus local sources pushing outward
// (a helicopter's downwash), horizontal (x, z) m/s.

struct WindSourceGpu {
    // centre at the first step's time; w: radius (m)
    start: vec4f,
    // centre at the last step's time; w: strength (m/s)
    finish: vec4f,
}

struct Wind {
    // xyz: global velocity (m/s); w: source count
    global: vec4f,
    sources: array<WindSourceGpu, 8>,
}

// 1 + gusts: two waves travelling downwind (40 and 13 m), one across.
fn wind_gust(p: vec2f, along: vec2f, speed: f32, t: f32) -> f32 {
    let x = dot(p, along);
    let y = p.x * along.y - p.y * along.x;
    let c = 0.8 * speed;
    return 1.0 + 0.25 * sin(0.157 * (x - c * t))
        + 0.12 * sin(0.483 * (x - c * t) + 1.3)
        + 0.08 * sin(0.11 * y + 0.9 * t);
}

// Outward push of a source centred at c: strength (1 - (d / radius)^2)^2.
fn wind_source_push(p: vec3f, c: vec3f, radius: f32, strength: f32) -> vec2f {
    let d = p - c;
    let q = min(dot(d, d) / (radius * radius), 1.0);
    let f = (1.0 - q) * (1.0 - q);
    let h = d.xz;
    return h / max(length(h), 0.5) * (strength * f);
}

// The wind at p, time t; s: fraction of the frame's steps (sources move
// from `start` to `finish`).
fn wind_at(w: Wind, p: vec3f, t: f32, s: f32) -> vec2f {
    let g = w.global.xz;
    let speed = length(g);
    var v = vec2f(0.0);
    if (speed > 0.0) {
        v = g * wind_gust(p.xz, g / speed, speed, t);
    }
    return v + wind_sources_push(w, p, s);
}

// The local sources alone (particles add them to the global wind).
fn wind_sources_push(w: Wind, p: vec3f, s: f32) -> vec2f {
    var v = vec2f(0.0);
    let n = min(u32(w.global.w), 8u);
    for (var i = 0u; i < n; i++) {
        let src = w.sources[i];
        let c = mix(src.start.xyz, src.finish.xyz, s);
        v += wind_source_push(p, c, src.start.w, src.finish.w);
    }
    return v;
}
