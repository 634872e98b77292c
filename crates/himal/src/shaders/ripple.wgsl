// V2 grass ripple (docs/techniques/V2.md "Grass"): a damped wave equation
// on a 128 x 128 grid of 0.25 m cells around the camera, pressed down by
// the wind sources (passes/vegetation/ripple.wgsl steps it; CPU twin
// passes/vegetation/ripple.rs). Cells are addressed by world cell modulo
// the grid size, so the window scrolls with the camera without copying;
// each cell remembers which world cell it holds, and a cell that held
// another one reads as flat. The grass vertex stage bends blade tips
// along the height's gradient (`ripple_bend`): outward from a source.
// The importer declares `ripple` (binding 12 in the G-buffer and shadow
// casters; read_write in the step).
#import scene

struct RippleHeader {
    // window origin (world cell of its corner), the half this frame's step
    // reads (0 or 1; it writes and the draws read the other), cells per side
    window: vec4i,
    // cell size (m), step (s), wave speed (m/s), damping (1/s)
    params: vec4f,
}

struct Ripple {
    header: RippleHeader,
    // halves 0 and 1: per cell (height, velocity, world cell x, z; exact
    // as f32 within 4,000 km); then halves 0 and 1 of the gradients (d/dx, d/dz of the
    // height, world cell x, z)
    cells: array<vec4f>,
}

// Metres of tip offset per unit slope of the ripple, and the largest.
const RIPPLE_BEND: f32 = 3.0;
const RIPPLE_BEND_MAX: f32 = 0.3;

fn ripple_slot(c: vec2i, n: i32) -> u32 {
    let m = ((c % n) + n) % n;
    return u32(m.x + m.y * n);
}

fn ripple_inside(h: RippleHeader, c: vec2i) -> bool {
    let l = c - h.window.xy;
    return all(l >= vec2i(0)) && all(l < vec2i(h.window.w));
}

// Cell `c`'s entry in `part` (0, 1: heights and velocities; 2, 3:
// gradients) of the importer's `ripple` buffer, or zero where the window
// does not hold it (outside, or a slot still holding another cell).
fn ripple_entry(c: vec2i, part: u32) -> vec2f {
    let h = ripple.header;
    let n = h.window.w;
    if (!ripple_inside(h, c)) {
        return vec2f(0.0);
    }
    let e = ripple.cells[part * u32(n * n) + ripple_slot(c, n)];
    if (e.z != f32(c.x) || e.w != f32(c.y)) {
        return vec2f(0.0);
    }
    return e.xy;
}

// V2: the horizontal tip offset (m, x and z) of a grass blade at world xz
// `p` at full weight: the gradient (bilinear between cell centres) times
// RIPPLE_BEND, no longer than RIPPLE_BEND_MAX.
fn ripple_bend(p: vec2f) -> vec2f {
    let h = ripple.header;
    let q = p / h.params.x - 0.5;
    let c = vec2i(floor(q));
    let f = q - floor(q);
    let part = 3u - u32(h.window.z);
    let g = mix(mix(ripple_entry(c, part), ripple_entry(c + vec2i(1, 0), part), f.x),
                mix(ripple_entry(c + vec2i(0, 1), part), ripple_entry(c + vec2i(1, 1), part), f.x), f.y);
    var b = g * RIPPLE_BEND;
    let l = length(b);
    if (l > RIPPLE_BEND_MAX) {
        b *= RIPPLE_BEND_MAX / l;
    }
    return b;
}

// V2: the ripple's offset of grass or bush vertex `position` (card uv) of
// object o at world `world`: the bend times the card's sway weight (0 for
// anything else; trees have their bones, params.y < 0).
fn grass_ripple(o: Object, position: vec3f, uv: vec2f, world: vec3f) -> vec4f {
    let p = foliage_pattern(o);
    if ((p != FOLIAGE_GRASS && p != FOLIAGE_LEAVES) || o.params.y < 0.0) {
        return vec4f(0.0);
    }
    let b = ripple_bend(world.xz) * foliage_sway_weight(o, position, uv);
    return vec4f(b.x, 0.0, b.y, 0.0);
}
