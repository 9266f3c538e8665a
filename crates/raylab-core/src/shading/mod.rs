//! How surfaces and lights shade: BSDFs ([`bsdf`]), what a part is made of
//! ([`material`]), textures, normal and height maps ([`texture`], [`relief`]), and the lights
//! ([`light`]: the lab's point light and its equation 27, area lights, the spot). Uses only
//! [`crate::base`].

pub mod bsdf;
pub mod light;
pub mod material;
pub mod relief;
pub mod texture;
