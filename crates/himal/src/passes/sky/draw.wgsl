// sky: Preetham sky radiance and the sun disk where no geometry was drawn
// (depth test Equal against the cleared reverse-Z value 0). TECHNIQUES L1 (foundation).
// Bindings: view, sky (uniform SkyParams). CPU twin: passes/sky/preetham.rs.
#import view
#import sky

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> sky: SkyParams;

struct VertexOut {
    // invariant: the depth test Equal 0 must see exactly the written value
    @builtin(position) @invariant clip: vec4f,
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> VertexOut {
    var out: VertexOut;
    out.clip = fullscreen_clip(i);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4f {
    let dir = view_ray(view, in.clip.xy * view.viewport.zw);
    let c = preetham_sky_radiance(sky, dir) + sun_disk_radiance(sky, dir);
    return vec4f(c, 1.0);
}
