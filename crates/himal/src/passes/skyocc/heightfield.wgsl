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
    let world = object_world(o, o.model, position, vec2f(0.0), false, 0.0);
    var out: HeightOut;
    out.clip = sector.view_proj * world;
    out.height = world.y;
    return out;
}

@fragment
fn fs_main(in: HeightOut) -> @location(0) vec4f {
    return vec4f(in.height, 0.0, 0.0, 1.0);
}
