//! The geometry stage: everything about the disk light and the casters that needs no GPU.

pub mod bvh;
pub mod oracle;
pub mod ray;
