//! What the queries answer: a [`Hit`], sixteen of them in lanes ([`HitLanes`]), and the work a
//! query did ([`TraversalCost`]).

/// A closest hit: the triangle's index in the scene and `t`, `u`, `v` exactly as
/// [`crate::shapes::intersect::intersect_triangle`] computes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub index: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// The closest hits of up to sixteen rays side by side, one lane a ray (structure of arrays):
/// lane `i` holds ray `i`'s [`Hit`], its `index` [`HitLanes::MISS`] where the ray met nothing.
/// What [`super::Accel::closest_lanes`] hands back, so that an integrator can read sixteen hits'
/// triangles at once ([`HitLanes::get`] gives one).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct HitLanes {
    pub t: [f32; 16],
    pub index: [u32; 16],
    pub u: [f32; 16],
    pub v: [f32; 16],
}

impl HitLanes {
    /// A lane's `index` where its ray met nothing.
    pub const MISS: u32 = u32::MAX;

    /// No hit in any lane, `t` at `t_max` (the limit a traversal compares against).
    #[inline(always)]
    pub fn new(t_max: f32) -> Self {
        Self {
            t: [t_max; 16],
            index: [Self::MISS; 16],
            u: [0.0; 16],
            v: [0.0; 16],
        }
    }

    /// Lane `i` holds `hits[i]` (at most sixteen); the lanes of misses, and those past the
    /// hits, none (`t` at `t_max`, as [`HitLanes::new`] leaves them).
    #[inline(always)]
    pub fn of(hits: &[Option<Hit>], t_max: f32) -> Self {
        debug_assert!(hits.len() <= 16);
        let mut lanes = Self::new(t_max);
        for (lane, &hit) in hits.iter().enumerate() {
            if hit.is_some() {
                lanes.set(lane, hit);
            }
        }
        lanes
    }

    /// Lane `lane`'s hit, if its ray met something.
    #[inline(always)]
    pub fn get(&self, lane: usize) -> Option<Hit> {
        (self.index[lane] != Self::MISS).then(|| Hit {
            index: self.index[lane],
            t: self.t[lane],
            u: self.u[lane],
            v: self.v[lane],
        })
    }

    /// Puts `hit` in lane `lane` (a miss: `None`).
    #[inline(always)]
    pub fn set(&mut self, lane: usize, hit: Option<Hit>) {
        let h = hit.unwrap_or(Hit {
            index: Self::MISS,
            t: f32::INFINITY,
            u: 0.0,
            v: 0.0,
        });
        self.t[lane] = h.t;
        self.index[lane] = h.index;
        self.u[lane] = h.u;
        self.v[lane] = h.v;
    }

    /// The lanes whose ray met something: bit `i` for lane `i`.
    #[inline(always)]
    pub fn hits(&self) -> u16 {
        let mut bits = 0u16;
        for (lane, &index) in self.index.iter().enumerate() {
            bits |= u16::from(index != Self::MISS) << lane;
        }
        bits
    }
}

/// The work one closest-hit query did ([`super::Accel::closest_counting`]): what the workbench's
/// BVH-cost view shows per pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TraversalCost {
    /// Interior nodes visited: each tests the boxes of all its children at once (eight for the
    /// wide BVH, two for the binary one). Leaves are not counted here but by their triangles.
    pub nodes: u32,
    /// Triangles tested: the real triangles of every leaf packet tested, not the packets'
    /// empty lanes (see [`super::wide::Bvh8::closest_counting`]); every triangle for the flat loop
    /// and the brute-force loop.
    pub triangles: u32,
}

impl TraversalCost {
    /// Nodes plus triangles, unweighted: the one number the cost view maps to colour. Plain
    /// counts can be checked by hand on a small tree; weighting them (the build's SAH takes a
    /// node visit as about four triangle tests, 1 against 0.25) would be a model of the time,
    /// not a count of the work.
    pub fn total(self) -> u32 {
        self.nodes + self.triangles
    }
}
