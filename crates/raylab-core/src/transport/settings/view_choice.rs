//! The debug views by name: what the viewport shows instead of the shaded image. Rendered by
//! [`crate::transport::view`].

use serde::{Deserialize, Serialize};

use crate::base::named::named_enum;

/// What the stage shows: the shaded image or one of the debug views.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum View {
    /// The rendered image (the chosen stage).
    #[default]
    Shaded,
    /// The shading normal at the first hit, as colour.
    Normals,
    /// The distance `t` to the first hit, white (near) to black (far).
    Depth,
    /// The barycentric coordinates `(1 − u − v, u, v)` of the first hit, as colour.
    Barycentric,
    /// A colour per triangle.
    Triangle,
    /// The work of each primary ray's closest-hit query, as a heat map.
    BvhCost,
    /// Whether the first hit sees the light: lit, blocked, or facing away.
    Shadow,
    /// How noisy each pixel's mean still is, from the spread of its samples.
    Variance,
    /// The caustic photons of the first pass, splatted as dots where the camera sees them.
    Photons,
}

named_enum!(View as "view" {
    Shaded => "shaded", "Shaded (the stage)";
    Normals => "normals", "Normals";
    Depth => "depth", "Depth t";
    Barycentric => "barycentric", "Barycentric u, v";
    Triangle => "triangle", "Triangle id";
    BvhCost => "bvh-cost", "BVH cost";
    Shadow => "shadow", "Shadow rays";
    Variance => "variance", "Variance";
    Photons => "photons", "Photons (caustic map)";
});

impl View {
    /// One line on what the view shows, for a selector's tooltip.
    pub fn description(self) -> &'static str {
        match self {
            View::Shaded => "the rendered image of the chosen stage",
            View::Normals => {
                "the shading normal n at each pixel's first hit (a normal map's where there is one), as (n + 1)/2"
            }
            View::Depth => "the distance t to each pixel's first hit: near white, far black",
            View::Barycentric => "the hit's barycentric coordinates (1 − u − v, u, v) as RGB",
            View::Triangle => "a colour per triangle, to see the mesh",
            View::BvhCost => "nodes visited + triangles tested per primary ray, as a heat map",
            View::Shadow => "whether the first hit sees the light's centre, or faces away",
            View::Variance => "the variance of each pixel's mean over its samples, as a heat map",
            View::Photons => {
                "the caustic photons of the first pass as dots, coloured by their power"
            }
        }
    }

    /// Whether [`render_view`] traces this view from primary rays (all but the shaded image
    /// and the variance map, which come from the renderer's film).
    pub fn is_traced(self) -> bool {
        match self {
            View::Shaded | View::Variance => false,
            View::Normals
            | View::Depth
            | View::Barycentric
            | View::Triangle
            | View::BvhCost
            | View::Shadow
            | View::Photons => true,
        }
    }

    /// The bytes a pixel of this view takes while it is made ([`render_view`]; the shaded
    /// image as [`crate::transport::render::try_render`] makes it): its linear image (12 bytes), and the
    /// raw values of a traced view beside it (an optional vector: 16; an optional distance,
    /// triangle index or a traversal cost: 8; a shadow state: 1). The variance view renders
    /// into a film that tracks the noise (the sum, 12, and the squares, 4) beside one pass
    /// (12), then makes its variances (4) and image (12) while the film is still there.
    pub fn bytes_per_pixel(self) -> u64 {
        let image = 12;
        image
            + match self {
                View::Shaded => 0,
                View::Normals | View::Barycentric => 16,
                View::Depth | View::Triangle | View::BvhCost => 8,
                View::Shadow => 1,
                View::Variance => 20,
                View::Photons => 4,
            }
    }
}
