// Constants every shader shares; one definition (the CPU twins use
// std::f32::consts). Typed f32, so expressions with them fold in f32 as the
// per-module copies they replace did.

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;
const HALF_PI: f32 = 1.57079632679490;
