//! S3 local-light shadow atlas allocator (pure CPU).
