//! The scene and how rays meet it: the triangle test ([`intersect`], the lab's
//! `closest_intersection`), the BVH and ray packets ([`accel`]), and the scenes ([`scene`]: the
//! lab's Cornell box, models, terrain, water), built from [`crate::shading`]'s materials and
//! lights.

pub mod accel;
pub mod intersect;
pub mod scene;
