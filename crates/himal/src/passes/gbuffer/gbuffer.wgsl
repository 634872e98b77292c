// gbuffer: rasterise scene geometry into the G-buffer (TECHNIQUES M1-M3).
// Targets: 0 albedo Rgba8UnormSrgb (rgb albedo, a material AO)
//          1 frame  Rgb10a2Unorm   (tangent frame quaternion, smallest three + index; M3)
//          2 material Rgba8Unorm   (glossiness, reflectance, metallic|foliage, anisotropy; M1,
//                                   V5: shaders/gbuffer_material.wgsl)
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
// V3 impostors: the atlas planes (group 0, bindings 8-10) and the grid's
// vertex and pixel stages, taken by VEGETATION draws of uv1.x < 0 vertices.
#import impostor_atlas
// V2: grass bends with the ripple grid around the camera.
#import ripple
// V5: grass, bush and leaf cards and impostor leaves mark the material's blue channel.
#import gbuffer_material

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(2) var<storage, read> instances: array<u32>;
@group(0) @binding(12) var<storage, read> ripple: Ripple;

override VEGETATION: bool = false;
// E2: the pipeline of the GPU lists fading between levels (screen-door
// discard by the instance's fade code); vegetation always applies it.
override DITHER: bool = false;
// `--view lod`: the level these draws are at (< 0: not that view).
override LOD_VIEW: f32 = -1.0;
// `--view impostor`: impostor pixels tinted by capture (others unchanged).
override IMPOSTOR_VIEW: bool = false;

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
    // V3 impostor pixels: p (centre-relative, units of R), and flat the
    // viewer direction w (tree space) with the atlas layer (< 0: not one)
    @location(9) impostor_p: vec3f,
    @location(10) @interpolate(flat) impostor_w: vec4f,
    @location(11) @interpolate(flat) object: u32,
}

@vertex
fn vs_main(in: GBufferVertexIn) -> VertexOut {
    let entry = instances[in.instance];
    let o = objects[instance_object(entry)];
    var v = object_vertex(o, in, view.view_proj, view.prev_view_proj, VEGETATION, view.time.xy);
    if (VEGETATION) {
        // The ripple's bend moves both positions alike: its own change
        // between frames is left out of the motion vectors.
        let bend = grass_ripple(o, in.position, in.uv, v.world.xyz);
        v.world += bend;
        v.prev_world += bend;
        v.clip = view.view_proj * v.world;
        v.prev_clip = view.prev_view_proj * v.prev_world;
    }
    var out: VertexOut;
    out.impostor_w = vec4f(0.0, 0.0, 1.0, -1.0);
    out.impostor_p = vec3f(0.0);
    out.object = instance_object(entry);
    let layer = impostor_layer(in.uv1);
    if (VEGETATION && layer >= 0) {
        // Face the camera (its position, or against an orthographic view).
        let centre = (o.model * vec4f(in.position, 1.0)).xyz;
        var toward = view.camera_position.xyz - centre;
        if (is_orthographic(view)) {
            toward = -view.camera_forward.xyz;
        }
        let g = impostor_object_vertex(o.normal_matrix, layer, in.position, in.tangent.w, in.uv, toward);
        v.world = impostor_world(o, g.local, false, view.time.x);
        v.prev_world = impostor_world(o, g.local, true, view.time.y);
        v.clip = view.view_proj * v.world;
        v.prev_clip = view.prev_view_proj * v.prev_world;
        // The fragment stage reads the raw tint and bark colours.
        v.normal = in.normal;
        v.tangent = in.tangent.xyz;
        out.impostor_p = g.p;
        out.impostor_w = vec4f(g.w, f32(layer));
    }
    out.uv = in.uv;
    if (VEGETATION && layer >= 0) {
        // The bark's glossiness, for the fragment stage.
        out.uv = vec2f(in.uv1.y, 0.0);
    }
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
    var foliage = 0.0;
    if ((DITHER || VEGETATION) && !lod_dither_keep(in.fade, in.clip.xy)) {
        discard;
    }
    if (VEGETATION && in.impostor_w.w >= 0.0) {
        return impostor_gbuffer(in);
    }
    if (VEGETATION) {
        if (foliage_alpha(in.pattern, in.uv) < 0.5) {
            discard;
        }
        // Cards are leaves; trunks and bark (pattern 0, or tinted) are not.
        if (in.pattern == FOLIAGE_GRASS || in.pattern == FOLIAGE_LEAVES) {
            foliage = 1.0;
        }
        // Grass normals lean up on both faces: mirror only the horizontal
        // part; bush normals are the bush's outward normal on both faces.
        if (!front && in.pattern == FOLIAGE_GRASS) {
            n = vec3f(-n.x, n.y, -n.z);
        }
        // V5: tree leaves flutter per pixel, more in a stronger wind (the
        // speed at the trunk, 0 with the waves off).
        let first = object_tree_first(objects[in.object]);
        if (first >= 0) {
            let speed = objects[u32(first)].params.y;
            n = leaf_flutter_normal(n, normalize(in.tangent.xyz), in.uv, view.time.x, speed);
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
    let m = clamp(in.surface, vec4f(0.0), vec4f(1.0));
    out.material = vec4f(m.xy, gbuffer_metallic_foliage(m.z, foliage), m.w);
    out.motion = gbuffer_motion(in.curr_clip, in.prev_clip);
    return out;
}

// V3: an impostor pixel from the blended captures: albedo mix(bark,
// mix(leaf, tint, t), leaf fraction) (impostor::albedo), the captured
// normal taken to world space, the leaf's or the bark's material by the
// same fraction. Vertex packing: scene/tree/impostor_level.rs.
fn impostor_gbuffer(in: VertexOut) -> GBufferOut {
    let px = impostor_pixel(i32(in.impostor_w.w), in.impostor_w.xyz, in.impostor_p);
    if (px.cover < 0.5) {
        discard;
    }
    let o = objects[in.object];
    let leaf = px.leaf / px.cover;
    let bark = in.tangent.xyz;
    // in.color is already tinted by the object (vs_main).
    let ot = object_tint(o);
    let albedo = mix(bark * ot, mix(in.color.rgb, in.normal * ot, px.tint / px.cover), leaf);
    var n = (o.normal_matrix * vec4f(px.normal, 0.0)).xyz;
    if (dot(n, n) < 1e-12) {
        n = vec3f(0.0, 1.0, 0.0);
    }
    n = normalize(n);
    let helper = select(vec3f(0.0, 1.0, 0.0), vec3f(1.0, 0.0, 0.0), abs(n.y) > 0.9);
    let tbn = shading_frame(n, vec4f(normalize(cross(helper, n)), 1.0));
    var out: GBufferOut;
    out.albedo = vec4f(albedo, in.color.a);
    if (LOD_VIEW >= 0.0) {
        out.albedo = vec4f(lod_view_albedo(u32(LOD_VIEW), albedo), in.color.a);
    }
    if (IMPOSTOR_VIEW) {
        out.albedo = vec4f(impostor_view_albedo(in.impostor_w.xyz), 1.0);
    }
    out.frame = pack_quat(frame_to_quat(tbn[0], tbn[1], tbn[2]));
    // The bark's glossiness (uv.x here), the rest the leaves'.
    // The leaf fraction is the pixel's leaf amount (V5).
    let bark_surface = vec4f(in.uv.x, in.surface.yzw);
    let m = clamp(mix(bark_surface, in.surface, leaf), vec4f(0.0), vec4f(1.0));
    out.material = vec4f(m.xy, gbuffer_metallic_foliage(m.z, leaf), m.w);
    out.motion = gbuffer_motion(in.curr_clip, in.prev_clip);
    return out;
}

// `--view impostor`: impostor pixels in the saturated hue of the capture
// with the largest weight (9 hues, the top one the ninth).
fn impostor_view_albedo(w: vec3f) -> vec3f {
    let b = impostor_blend(w);
    var k = select(b.captures.x, b.captures.y, b.weights.y > b.weights.x);
    if (b.weights.z > max(b.weights.x, b.weights.y)) {
        k = b.captures.z;
    }
    let h = f32(k) / 9.0;
    return clamp(abs(fract(h + vec3f(0.0, 2.0 / 3.0, 1.0 / 3.0)) * 6.0 - 3.0) - 1.0, vec3f(0.0), vec3f(1.0));
}
