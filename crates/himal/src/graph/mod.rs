//! Frame graph: typed versioned handles, compile (order, cull, usages, pool), execute with timestamps.
