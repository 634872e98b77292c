// The receiver of a mask pixel (shadows.mask and shadows.mask_tiles, #23):
// world position at the pixel centre `frag_xy`, G-buffer normal (`frame`:
// the packed tangent frame texel), view distance along the camera axis.
#import view
#import tangent_frame
#import shadow

struct Receiver {
    p: vec3f,
    n: vec3f,
    dist: f32,
}

fn shadow_receiver(view: View, params: ShadowMaskParams, frag_xy: vec2f, d: f32, frame: vec4f) -> Receiver {
    var r: Receiver;
    r.p = world_at_fragment(view, frag_xy, d);
    r.n = quat_to_frame(unpack_quat(frame))[2];
    r.dist = dot(r.p - view.camera_position.xyz, params.camera_forward.xyz);
    return r;
}
