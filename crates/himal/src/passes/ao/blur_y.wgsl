// ao.blur_y / ao.blur_y_stf: vertical cross-bilateral blur (TECHNIQUES O3) with the
// selective temporal filter merged in (O2, STF = true), as in the talk:
//   w_i = ViewDepth(View_(i-1), P_i), w_(i-1) = Z_(i-1)(uv_(i-1)) (clamp to border, Z = 0),
//   uv_(i-1) without the jitter change between the frames
//   if |1 - w_i / w_(i-1)| < eps and the pixel is unstable (or the filter is not selective):
//       AO_i = (N_(i-1) AO_(i-1) + AO_i) / (N_(i-1) + 1),  N_i = min(N_(i-1) + 1, N_max)
//   else N_i = 1
// Target: Rgba16Float (AO_i, Z_i = linear depth in this frame's view, N_i): the next
// frame's history. Bindings: params, view, blurred_x, depth, stability_load, history
// (previous frame, AO fetched bilinearly), linear_sampler.
// fs_ssdo (O4, with STF): a second target, Rg16Float (c1, c2), the directional
// coefficients blurred with the AO's weights and filtered with its N; its own
// history ring (history_dir).
// CPU twin: reference.rs `temporal_filter`.
#import view
#import ao
#import fullscreen

override STF: bool = true;

@group(0) @binding(0) var<uniform> params: AoParams;
@group(0) @binding(1) var<uniform> view: View;
@group(0) @binding(2) var blurred_x: texture_2d<f32>;
@group(0) @binding(3) var depth: texture_depth_2d;
@group(0) @binding(4) var stability_load: texture_2d<f32>;
@group(0) @binding(5) var history: texture_2d<f32>;
@group(0) @binding(6) var linear_sampler: sampler;
@group(0) @binding(7) var history_dir: texture_2d<f32>;

struct Out {
    @location(0) history: vec4f,
    @location(1) dir: vec4f,
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    return blur_and_filter(frag, false).history;
}

// The SSDO pipeline (two targets).
@fragment
fn fs_ssdo(@builtin(position) frag: vec4f) -> Out {
    return blur_and_filter(frag, true);
}

fn blur_and_filter(frag: vec4f, ssdo: bool) -> Out {
    let px = vec2i(frag.xy);
    let blurred = ao_cross_bilateral(blurred_x, linear_sampler, px, vec2i(0, 1), params);
    var ao = blurred.x;
    var dir = blurred.zw;
    var n = 1.0;
    let d = textureLoad(depth, px, 0);
    if (STF && d > 0.0) {
        let p = world_at_fragment(view, frag.xy, d);
        let prev_clip = view.prev_view_proj * vec4f(p, 1.0);
        let w_i = prev_clip.w;
        // Both matrices carry their frame's jitter: remove its change so a static
        // surface reprojects onto itself (jitter-free motion, as passes/aa).
        let prev_uv = vec2f(0.5, -0.5) * prev_clip.xy / prev_clip.w + 0.5
            + (params.jitter.zw - params.jitter.xy) * params.full_size.zw;
        let prev_px = vec2i(floor(prev_uv * params.full_size.xy));
        let inside = all(prev_px >= vec2i(0)) && all(prev_px < vec2i(params.full_size.xy)) && w_i > 0.0;
        var w_prev = 0.0;
        var n_prev = 0.0;
        if (inside) {
            let h = textureLoad(history, prev_px, 0);
            w_prev = h.y;
            n_prev = h.z;
        }
        let q = min(px / i32(params.hbao_steps.z), vec2i(params.ao_size.xy) - 1);
        let stable = textureLoad(stability_load, q, 0).x > 0.5;
        // |1 - w_i / w_(i-1)| < eps, written without the division (w_(i-1) = 0 fails).
        let same_surface = abs(w_prev - w_i) < params.stf.x * w_prev;
        if (same_surface && !(stable && params.stf.w > 0.5)) {
            let ao_prev = textureSampleLevel(history, linear_sampler, prev_uv, 0.0).x;
            ao = (n_prev * ao_prev + ao) / (n_prev + 1.0);
            if (ssdo) {
                let dir_prev = textureSampleLevel(history_dir, linear_sampler, prev_uv, 0.0).xy;
                dir = (n_prev * dir_prev + dir) / (n_prev + 1.0);
            }
            n = min(n_prev + 1.0, params.stf.y);
        }
    }
    return Out(vec4f(ao, blurred.y, n, 1.0), vec4f(dir, 0.0, 1.0));
}
