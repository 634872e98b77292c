// skyocc.heightfield: top-down orthographic render of one sector (plus its
// apron) of the scene's opaque geometry (TECHNIQUES L2). The depth test keeps
// the highest surface (depth 0 at the top of the scene); the colour target
// stores its world height (R32Float, cleared to the bottom of the scene).
// Vegetation is not drawn (swaying cards would flicker the sky occlusion).
// Bindings: sector (uniform SectorView), objects (as gbuffer).

#import scene
#import object_vertex

struct SectorView {
    view_proj: mat4x4f,
    // xy world x, z of texel (0, 0)'s corner; z the texel size (m)
    origin: vec4f,
}

@group(0) @binding(0) var<uniform> sector: SectorView;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(2) var<storage, read> instances: array<u32>;

struct HeightOut {
    @builtin(position) clip: vec4f,
    @location(0) height: f32,
}

@vertex
fn vs_main(@location(0) position: vec3f, @builtin(instance_index) instance: u32) -> HeightOut {
    let o = objects[instance_object(instances[instance])];
    let world = object_rest(o, position);
    var out: HeightOut;
    out.clip = sector.view_proj * world;
    out.height = world.y;
    return out;
}

// Height change per texel beyond which a triangle counts as edge-on (88
// degrees at 25 cm texels): seen from above, a wall's sliver triangles
// have nearly no area, and their fragments' heights extrapolate past the
// wall's top (a roof corner rose 2.2 m over its house). Their top edges
// belong to the surfaces above them anyway.
const EDGE_ON: f32 = 8.0;

@fragment
fn fs_main(in: HeightOut) -> @location(0) vec4f {
    if (max(abs(dpdx(in.height)), abs(dpdy(in.height))) > EDGE_ON) {
        discard;
    }
    return vec4f(in.height, 0.0, 0.0, 1.0);
}
