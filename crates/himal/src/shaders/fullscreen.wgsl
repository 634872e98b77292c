// The vertex stage of every full-screen pass: one triangle covering the
// screen (`fullscreen_clip` in view.wgsl). A pass imports it instead of
// writing its own `vs_main`.
#import view

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    return fullscreen_clip(i);
}
