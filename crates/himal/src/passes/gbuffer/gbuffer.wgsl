// gbuffer: rasterise scene geometry into the G-buffer (TECHNIQUES M1-M3).
// Targets: 0 albedo Rgba8UnormSrgb (rgb albedo, a material AO)
//          1 frame  Rgb10a2Unorm   (tangent frame quaternion, smallest three + index; M3)
//          2 material Rgba8Unorm   (glossiness, reflectance, metallic, anisotropy; M1)
//          3 motion Rg16Float      (previous uv - current uv)
// Bindings: view (uniform View), objects (storage, per-object transforms; instance index = object).
// VEGETATION (override): the alpha-tested, swaying, double-sided pipeline
// (docs/techniques/vegetation.md); false keeps the opaque path free of discard.
// Source: McAuley, "Rendering the World of Far Cry 4", GDC 2015, Materials + Appendix A.
#import gbuffer_io
#import view
#import tangent_frame
#import scene
#import object_vertex
// Group 0 binding 3 (deform_prev): declared for the layout gbuffer.textured
// shares; these objects are never skinned.
#import deform

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(2) var<storage, read> instances: array<u32>;

override VEGETATION: bool = false;
// E2: the pipeline of the GPU lists fading between levels (screen-door
// discard by the instance's fade code); vegetation always applies it.
override DITHER: bool = false;
// `--view lod`: the level these draws are at (< 0: not that view).
override LOD_VIEW: f32 = -1.0;

struct VertexOut {
    @builtin(position) clip: vec4f,
    @location(0) normal: vec3f,
    @location(1) tangent: vec4f,
    @location(2) color: vec4f,
    @location(3) surface: vec4f,
    @location(4) curr_clip: vec4f,
    @location(5) prev_clip: vec4f,
    @location(6) uv: vec2f,
    @location(7) @interpolate(flat) pattern: u32,
    @location(8) @interpolate(flat) fade: u32,
}

@vertex
fn vs_main(in: GBufferVertexIn) -> VertexOut {
    let entry = instances[in.instance];
    let o = objects[instance_object(entry)];
    let v = object_vertex(o, in, view.view_proj, view.prev_view_proj, VEGETATION, view.time.xy);
    var out: VertexOut;
    out.uv = in.uv;
    out.pattern = 0u;
    out.fade = instance_fade(entry);
    if (VEGETATION) {
        out.pattern = foliage_pattern(o);
    }
    out.curr_clip = v.clip;
    out.prev_clip = v.prev_clip;
    out.clip = v.clip;
    out.normal = v.normal;
    out.tangent = vec4f(v.tangent, in.tangent.w);
    out.color = vec4f(in.color.rgb * object_tint(o), in.color.a);
    out.surface = in.surface;
    return out;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> GBufferOut {
    var n = normalize(in.normal);
    if ((DITHER || VEGETATION) && !lod_dither_keep(in.fade, in.clip.xy)) {
        discard;
    }
    if (VEGETATION) {
        if (foliage_alpha(in.pattern, in.uv) < 0.5) {
            discard;
        }
        // Grass normals lean up on both faces: mirror only the horizontal
        // part; bush normals are the bush's outward normal on both faces.
        if (!front && in.pattern == FOLIAGE_GRASS) {
            n = vec3f(-n.x, n.y, -n.z);
        }
    } else if (!front) {
        n = -n;
    }
    // Right-handed shading frame; a mirrored tangent's sign is consumed here (M3.md).
    let tbn = shading_frame(n, in.tangent);
    var out: GBufferOut;
    out.albedo = in.color;
    if (LOD_VIEW >= 0.0) {
        out.albedo = vec4f(lod_view_albedo(u32(LOD_VIEW), in.color.rgb), in.color.a);
    }
    out.frame = pack_quat(frame_to_quat(tbn[0], tbn[1], tbn[2]));
    out.material = clamp(in.surface, vec4f(0.0), vec4f(1.0));
    out.motion = gbuffer_motion(in.curr_clip, in.prev_clip);
    return out;
}
