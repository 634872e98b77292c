//! GPU context: adapter choice, device, errors, read-back, timestamps.
