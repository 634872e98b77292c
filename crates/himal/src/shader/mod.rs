//! WGSL composition: shared modules imported with `#import name`, line map, naga reflection.
