//! Shadow rays given as lanes, as the integrators' shading makes them ([`SegmentLanes`]).

use crate::base::geometry::Ray;

/// Up to sixteen shadow rays as lanes (structure of arrays), as the lab's shading makes them:
/// origins, directions and lengths per lane, and `cast`, bit `i` set where lane `i` holds a ray.
/// [`super::Accel::occluded_lanes`] traces them without copying them into an array of rays first.
#[derive(Clone, Copy, Debug)]
pub struct SegmentLanes<'a> {
    pub origin: [&'a [f32; 16]; 3],
    pub direction: [&'a [f32; 16]; 3],
    pub t_max: &'a [f32; 16],
    pub cast: u16,
}

impl SegmentLanes<'_> {
    /// Lane `i`'s ray and length.
    pub fn ray(&self, i: usize) -> (Ray, f32) {
        let v = |a: [&[f32; 16]; 3]| glam::Vec3::new(a[0][i], a[1][i], a[2][i]);
        (
            Ray {
                origin: v(self.origin),
                direction: v(self.direction),
            },
            self.t_max[i],
        )
    }
}
