// probes.transfer (L5): every probe of every pool slot, its SH2 radiance
// for this frame's sky and sun: L_i = sum_j T[i][j] S_j per colour channel.
// Transfer is stored as f16 pairs, 24 words per probe, channel-major
// (passes/indirect/cell.rs). CPU twin: passes/indirect/reference.rs `transfer`.
#import indirect

@group(0) @binding(0) var<storage, read> params: IndirectParams;
@group(0) @binding(1) var<storage, read> cells: array<u32>;
// Three vec4 per probe: the r, g and b channel's four coefficients.
@group(0) @binding(2) var<storage, read_write> sh_probes: array<vec4f>;

fn t_at(base: u32, n: u32) -> f32 {
    let pair = unpack2x16float(cells[base + n / 2u]);
    return select(pair.x, pair.y, (n & 1u) == 1u);
}

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let k = id.x;
    if (k >= params.counts.x) {
        return;
    }
    let base = k * 24u;
    for (var c = 0u; c < 3u; c++) {
        let s = vec4f(params.lighting[0][c], params.lighting[1][c], params.lighting[2][c], params.lighting[3][c]);
        var out = vec4f(0.0);
        for (var i = 0u; i < 4u; i++) {
            let row = c * 16u + i * 4u;
            out[i] = t_at(base, row) * s.x + t_at(base, row + 1u) * s.y + t_at(base, row + 2u) * s.z
                + t_at(base, row + 3u) * s.w;
        }
        sh_probes[k * 3u + c] = out;
    }
}
