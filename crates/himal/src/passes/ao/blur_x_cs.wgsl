// ao.pack + ao.blur_x as one compute pass (#23, `AoSettings::compute_blur`):
// the taps of blur_x.wgsl (shaders/ao.wgsl `ao_cross_bilateral`, step (1, 0))
// read from a workgroup tile instead of a texture: a row segment of TILE
// pixels plus an apron of APRON texels each side, each packed (`ao_pack`,
// from depth and hbao) once per workgroup instead of written by ao.pack and
// fetched once per tap; the tile keeps f32 where the packed texture was f16. The apron is the largest radius (32) plus the
// second texel of the outermost bilinear tap; texels are clamped to the
// image when loaded, as the sampler's clamp to edge. A bilinear tap at
// r + 0.5 is the mean of texels r and r + 1 (the sampler's weights are 0.5).
// Output Rgba16Float (AO, Z, c1, c2): Rg16Float is no core storage format.
// CPU twin: reference.rs `pack`, then `blur`; GPU test tests/ao.rs `compute_blur_*`.
#import ao

const TILE: i32 = 128;
const APRON: i32 = 33;
const SPAN: i32 = 194; // TILE + 2 * APRON

// Storage, not uniform: the loop bounds read it (lavapipe recompiles per
// dispatch otherwise, docs/reliability.md).
@group(0) @binding(0) var<storage, read> params: AoParams;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var hbao: texture_2d<f32>;
@group(0) @binding(3) var linear_sampler: sampler;
@group(0) @binding(4) var blurred: texture_storage_2d<rgba16float, write>;

var<workgroup> row: array<vec4f, SPAN>;

// Texel at offset o from tile pixel t (|o| <= APRON).
fn tile_texel(t: i32, o: i32) -> vec4f {
    return row[t + APRON + o];
}

@compute @workgroup_size(128, 1, 1)
fn cs_main(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_id) lid: vec3u) {
    let p = params;
    let size = vec2i(textureDimensions(depth));
    let y = i32(wg.y);
    let x0 = i32(wg.x) * TILE;
    for (var i = i32(lid.x); i < SPAN; i += TILE) {
        let x = clamp(x0 - APRON + i, 0, size.x - 1);
        row[i] = ao_pack(p, depth, hbao, linear_sampler, vec2i(x, y));
    }
    workgroupBarrier();
    let t = i32(lid.x);
    if (x0 + t >= size.x) {
        return;
    }
    let c = tile_texel(t, 0);
    var total = vec4f(c.x, 1.0, c.zw);
    let radius = p.blur.x;
    var r = 1.0;
    let inner = select(radius, floor(radius * 0.5), p.blur.w > 0.5);
    for (; r <= inner; r += 1.0) {
        let o = i32(r);
        ao_blur_tap(tile_texel(t, o), r, c.y, 1.0, p, &total);
        ao_blur_tap(tile_texel(t, -o), r, c.y, 1.0, p, &total);
    }
    for (; r <= radius; r += 2.0) {
        let o = i32(r);
        let right = 0.5 * (tile_texel(t, o) + tile_texel(t, o + 1));
        let left = 0.5 * (tile_texel(t, -o) + tile_texel(t, -o - 1));
        ao_blur_tap(right, r + 0.5, c.y, 2.0, p, &total);
        ao_blur_tap(left, r + 0.5, c.y, 2.0, p, &total);
    }
    let out = vec4f(total.x / total.y, c.y, total.zw / total.y);
    textureStore(blurred, vec2i(x0 + t, y), out);
}
