//! The frames BSDFs work in: [`Frame`], an orthonormal basis around the shading normal, and
//! [`ShadingFrame`], that frame at a hit with the geometric normal's rules (the module's
//! documentation, "The geometric normal").

use glam::{Vec2, Vec3};

use super::{Bsdf, BsdfSample, same_hemisphere};
use crate::base::sampling::orthonormal_basis;

/// The smallest cos θ_o a [`ShadingFrame`] leaves between `wo` and its shading normal: a bent
/// normal keeps `wo` at least this far above the shading hemisphere (about 0.06° from
/// grazing), so BSDFs never see `wo` on or below their horizon.
pub const MIN_SHADING_COS: f32 = 1e-3;

/// An orthonormal, right-handed frame (s × t = n): the local coordinates a [`Bsdf`] works in,
/// with `n` as z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The first tangent, local x.
    pub s: Vec3,
    /// The second tangent, local y.
    pub t: Vec3,
    /// The normal, local z.
    pub n: Vec3,
}

impl Frame {
    /// The frame around the unit normal `n`, its tangents from Duff et al.'s branchless basis
    /// ([`orthonormal_basis`]). The tangents' azimuth is arbitrary, which suits the isotropic
    /// BSDFs here.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let (s, t) = orthonormal_basis(n);
        Self { s, t, n }
    }

    /// `v` (world) in local coordinates: its dot products with s, t and n.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// `v` (local) in world coordinates: x·s + y·t + z·n. The inverse of [`Frame::to_local`]
    /// (the frame is orthonormal, so the inverse is the transpose).
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.s + v.y * self.t + v.z * self.n
    }
}

/// The shading frame at a hit, with the geometric normal's rules (see the module's
/// documentation): built once per hit by [`ShadingFrame::new`], the one place those rules
/// live.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingFrame {
    /// The shading frame, its normal on the side of `wo` and bent so that cos θ_o ≥
    /// [`MIN_SHADING_COS`] where possible.
    frame: Frame,
    /// The geometric normal, flipped to the side of `wo`.
    geometric: Vec3,
    /// Whether `wo` was on the side the geometric normal as given points to (outside a glass
    /// object whose normals point out).
    front: bool,
}

impl ShadingFrame {
    /// The frame for a hit with unit `geometric_normal` (either orientation), a
    /// `shading_normal` (normalised here; zero or not finite means "none", the geometric one)
    /// and `wo_world` (unit, pointing away from the surface):
    ///
    /// 1. the geometric normal n_g is flipped to the side of `wo`, the shading normal n_s to
    ///    the side of n_g: the geometric normal decides the side;
    /// 2. if a = wo·n_s < ε = [`MIN_SHADING_COS`], n_s is blended towards n_g:
    ///    n_s ← normalize(n_s + t (n_g − n_s)) with t = (ε − a)/(b − a), b = wo·n_g. Then
    ///    wo·(n_s + t (n_g − n_s)) = ε, and since a blend of two unit vectors is at most unit
    ///    long, wo·n_s ≥ ε after normalising. The normal stays in the plane of the two and
    ///    moves no further than needed; if wo is itself within ε of the geometric surface
    ///    (b ≤ ε), n_s becomes n_g.
    ///
    /// Blending towards n_g, rather than rotating towards wo, keeps the mirror direction of a
    /// nearly grazing wo above the geometric surface.
    #[inline]
    pub fn new(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> ShadingFrame {
        let (ns, ng, front) = Self::normals(shading_normal, geometric_normal, wo_world);
        ShadingFrame {
            frame: Frame::from_normal(ns),
            geometric: ng,
            front,
        }
    }

    /// The shading normal [`ShadingFrame::new`] would use (rules 1 and 2: on the geometric
    /// side of `wo`, bent so that cos θ_o ≥ [`MIN_SHADING_COS`]), turned back to the side of
    /// `geometric_normal` as given. For a normal map's perturbed normal, which the lab's
    /// stages light by its cosine (equation 27) without a frame: the same rules, so the tilt
    /// never turns the normal away from the viewer (no black patches) nor across the surface
    /// it is measured against ([`crate::transport::integrator::Tracer::surface_with`]).
    #[inline]
    pub fn bent_normal(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> Vec3 {
        let (ns, _, front) = Self::normals(shading_normal, geometric_normal, wo_world);
        if front { ns } else { -ns }
    }

    /// The shading normal [`ShadingFrame::new`] would use (rules 1 and 2), on the side of
    /// `wo`: the normal a viewer from `wo` sees the surface with, as the denoiser's features
    /// record it ([`crate::transport::film::Seen`]).
    #[inline]
    pub fn seen_normal(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> Vec3 {
        Self::normals(shading_normal, geometric_normal, wo_world).0
    }

    /// Rules 1 and 2 of [`ShadingFrame::new`]: the shading normal and the geometric normal on
    /// the side of `wo`, the first bent, and whether `wo` is on the geometric normal's side.
    #[inline(always)]
    fn normals(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> (Vec3, Vec3, bool) {
        let front = wo_world.dot(geometric_normal) > 0.0;
        let ng = if front {
            geometric_normal
        } else {
            -geometric_normal
        };
        let ns = shading_normal.normalize_or_zero();
        let mut ns = if ns == Vec3::ZERO {
            ng
        } else if ns.dot(ng) < 0.0 {
            -ns
        } else {
            ns
        };
        let a = wo_world.dot(ns);
        if a < MIN_SHADING_COS {
            let b = wo_world.dot(ng);
            ns = if b > MIN_SHADING_COS {
                let t = (MIN_SHADING_COS - a) / (b - a);
                (ns + t * (ng - ns)).normalize()
            } else {
                ng
            };
        }
        (ns, ng, front)
    }

    /// The (bent) shading frame: its normal is local z for the BSDFs.
    #[inline]
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// The shading normal as used, on the side of `wo`.
    #[inline]
    pub fn shading_normal(&self) -> Vec3 {
        self.frame.n
    }

    /// The geometric normal, flipped to the side of `wo`.
    #[inline]
    pub fn geometric_normal(&self) -> Vec3 {
        self.geometric
    }

    /// Whether `wo` is on the side the geometric normal as given points to: for glass whose
    /// normals point out, whether the path arrives from outside.
    #[inline]
    pub fn front_face(&self) -> bool {
        self.front
    }

    /// A world direction in the shading frame's local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        self.frame.to_local(v)
    }

    /// A local direction in world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.frame.to_world(v)
    }

    /// Whether `wi_world` is on the same side of the *geometric* surface as `wo_world`:
    /// reflection if so, transmission if not (rule 3 of the module's documentation). A
    /// direction in the geometric plane counts as neither.
    #[inline]
    pub fn reflects(&self, wo_world: Vec3, wi_world: Vec3) -> bool {
        wo_world.dot(self.geometric) * wi_world.dot(self.geometric) > 0.0
    }

    /// `bsdf` as seen from the side of `wo`: the frame's normal always points to `wo`, so for
    /// a glass hit from inside (not [`ShadingFrame::front_face`]) the index ratio is inverted,
    /// ior → 1/ior; every other BSDF is two-sided and unchanged.
    #[inline]
    pub fn oriented(&self, bsdf: &Bsdf) -> Bsdf {
        match *bsdf {
            Bsdf::Glass { ior, tint } if !self.front => Bsdf::Glass {
                ior: 1.0 / ior,
                tint,
            },
            other => other,
        }
    }

    /// Whether the shading frame agrees with the geometric surface about `wi`: both call it
    /// reflection or both transmission.
    #[inline(always)]
    fn consistent(&self, wo_world: Vec3, wi_world: Vec3, wo_local: Vec3, wi_local: Vec3) -> bool {
        self.reflects(wo_world, wi_world) == same_hemisphere(wo_local, wi_local)
    }

    /// f(wo, wi) and the pdf with which [`ShadingFrame::sample_world`] draws `wi`, for world
    /// directions (unit, pointing away): the BSDF in the shading frame where the geometric
    /// surface and the shading frame agree whether `wi` is reflection or transmission, and
    /// `(0, 0)` where they disagree, so reflection-only BSDFs give nothing across the
    /// geometric surface and transmission must cross it.
    #[inline]
    pub fn eval_world(&self, bsdf: &Bsdf, wo_world: Vec3, wi_world: Vec3) -> (Vec3, f32) {
        let bsdf = self.oriented(bsdf);
        let wo = self.to_local(wo_world);
        let wi = self.to_local(wi_world);
        if !self.consistent(wo_world, wi_world, wo, wi) {
            return (Vec3::ZERO, 0.0);
        }
        (bsdf.eval(wo, wi), bsdf.pdf(wo, wi))
    }

    /// [`Bsdf::sample`] for a world `wo_world`, the sample's `wi` in world coordinates.
    /// `None` also where the sampled direction breaks rule 3 (a reflection below the
    /// geometric surface or a refraction that does not cross it): that light is absorbed, as
    /// [`ShadingFrame::eval_world`] gives it zero.
    #[inline]
    pub fn sample_world(
        &self,
        bsdf: &Bsdf,
        wo_world: Vec3,
        uc: f32,
        u: Vec2,
    ) -> Option<BsdfSample> {
        let bsdf = self.oriented(bsdf);
        let wo = self.to_local(wo_world);
        let s = bsdf.sample(wo, uc, u)?;
        let wi_world = self.to_world(s.wi);
        self.consistent(wo_world, wi_world, wo, s.wi)
            .then_some(BsdfSample { wi: wi_world, ..s })
    }
}

#[cfg(test)]
mod tests {
    use super::super::checks::{COLOUR, close, close3, dir, u2};
    use super::super::{flip_z, reflect, reflect_local};
    use super::*;
    use crate::base::sampling::{Rng, uniform_hemisphere};
    use crate::shading::bsdf::fresnel_dielectric;

    /// Frames are orthonormal and right-handed (s × t = n), to_world inverts to_local, and n
    /// is local z: for 1000 random normals and ±z, and for the frames [`ShadingFrame::new`]
    /// builds from random shading normals, geometric normals and wo.
    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        let mut rng = Rng::new(8);
        let random_unit = |rng: &mut Rng| {
            Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            )
            .normalize()
        };
        let check = |f: Frame| {
            for (a, b) in [(f.s, f.t), (f.s, f.n), (f.t, f.n)] {
                assert!(a.dot(b).abs() < 1e-5, "{f:?}");
            }
            for v in [f.s, f.t, f.n] {
                assert!((v.length() - 1.0).abs() < 1e-5, "{f:?}");
            }
            assert!(
                (f.s.cross(f.t) - f.n).length() < 1e-5,
                "right-handed: {f:?}"
            );
            assert!((f.to_local(f.n) - Vec3::Z).length() < 1e-5);
            let v = Vec3::new(0.3, -0.5, 0.8);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        };
        check(Frame::from_normal(Vec3::Z));
        check(Frame::from_normal(-Vec3::Z));
        for _ in 0..1000 {
            check(Frame::from_normal(random_unit(&mut rng)));
            let (ns, ng, wo) = (
                random_unit(&mut rng),
                random_unit(&mut rng),
                random_unit(&mut rng),
            );
            let sf = ShadingFrame::new(ns, ng, wo);
            check(sf.frame());
            let g = sf.geometric_normal();
            assert!(wo.dot(g) >= 0.0 && (g - ng).length() * (g + ng).length() < 1e-6);
            assert!(sf.shading_normal().dot(g) >= 0.0, "on the geometric side");
            if wo.dot(g) > MIN_SHADING_COS {
                assert!(sf.to_local(wo).z >= MIN_SHADING_COS * (1.0 - 1e-3));
            }
        }
    }

    /// A shading normal tilted 53° (n_s = (0.8, 0, 0.6), geometric z) with wo = (−0.9, 0, 0.3)
    /// /|·| 18° above the geometric surface but below the shading one (wo·n_s = −0.54/0.949):
    /// the frame's normal is n_s blended towards z with t = (ε − a)/(b − a), leaving wo just
    /// above it (ε/|blend| = 1.107 ε), still tilted towards +x in the xz plane. The same with the geometric normal given as −z (two-sided), and with wo on the
    /// other side both normals flip to it. A shading normal with wo well above it is kept;
    /// one pointing against the geometric normal is flipped to its side.
    #[test]
    fn a_shading_normal_below_wo_is_bent_towards_the_geometric_one() {
        let ns = Vec3::new(0.8, 0.0, 0.6);
        let wo = Vec3::new(-0.9, 0.0, 0.3).normalize();
        let (a, b) = (wo.dot(ns), wo.dot(Vec3::Z));
        assert!(a < 0.0 && b > 0.0);
        let t = (MIN_SHADING_COS - a) / (b - a);
        let expected = (ns + t * (Vec3::Z - ns)).normalize();
        for ng in [Vec3::Z, -Vec3::Z] {
            let sf = ShadingFrame::new(ns, ng, wo);
            assert_eq!(sf.front_face(), ng == Vec3::Z);
            assert_eq!(sf.geometric_normal(), Vec3::Z);
            let n = sf.shading_normal();
            assert!((n - expected).length() < 1e-5, "{n} vs {expected}");
            // wo·n = ε/|n_s + t (n_g − n_s)|: the blend is shorter than unit (0.904 here),
            // so wo ends 1.107 ε above, no more.
            let cos_o = sf.to_local(wo).z;
            let blend = (ns + t * (Vec3::Z - ns)).length();
            assert!(close(cos_o, MIN_SHADING_COS / blend, 1e-3), "{cos_o}");
            assert!(
                (MIN_SHADING_COS..1.2 * MIN_SHADING_COS).contains(&cos_o),
                "{cos_o}"
            );
            // Bent from 53° to 18.4° off z (n = (0.315, 0, 0.949)): still towards +x.
            assert!(n.x > 0.3 && n.y.abs() < 1e-6 && n.z > 0.9, "{n}");
        }
        // The mirror image from behind: both normals flip to −wo's side, then bend the same.
        let back = ShadingFrame::new(ns, Vec3::Z, -wo);
        assert!(!back.front_face());
        assert_eq!(back.geometric_normal(), -Vec3::Z);
        assert!(
            (back.shading_normal() + expected).length() < 1e-5,
            "{back:?}"
        );
        assert!(back.to_local(-wo).z >= MIN_SHADING_COS * (1.0 - 1e-3));
        // wo well above: the shading normal is kept (normalised).
        let kept = ShadingFrame::new(2.0 * ns, Vec3::Z, Vec3::new(0.6, 0.0, 0.8));
        assert!((kept.shading_normal() - ns).length() < 1e-6);
        // A shading normal against the geometric one is turned to its side first.
        let turned = ShadingFrame::new(-ns, Vec3::Z, Vec3::new(0.6, 0.0, 0.8));
        assert!((turned.shading_normal() - ns).length() < 1e-6);
        // No shading normal: the geometric one.
        let none = ShadingFrame::new(Vec3::ZERO, Vec3::Z, -wo);
        assert_eq!(none.shading_normal(), -Vec3::Z);
    }

    /// With a tilted shading normal n_s = (0.5, 0, 1)/√1.25 over a geometric z and
    /// wo = 30° on the −x side: wi = (0.9, 0, −0.1)/|·| is above the shading surface but
    /// below the geometric one. In the shading frame alone the Lambertian and the rough
    /// conductor would give it light; [`ShadingFrame::eval_world`] gives (0, 0). wi = z,
    /// above both, gets ρ/π and pdf cos θ_i/π. Of 10,000 cosine samples through
    /// [`ShadingFrame::sample_world`] some are refused (the tilted lobe reaches below the
    /// geometric plane) and none returned is below it, each with the pdf eval_world gives.
    /// A mirror whose reflection about n_s would go below the geometric surface gives no
    /// sample.
    #[test]
    fn reflection_only_bsdfs_give_nothing_across_the_geometric_surface() {
        let ng = Vec3::Z;
        let ns = Vec3::new(0.5, 0.0, 1.0).normalize();
        let wo = dir(30f32.to_radians(), std::f32::consts::PI);
        let sf = ShadingFrame::new(ns, ng, wo);
        assert!((sf.shading_normal() - ns).length() < 1e-6, "not bent");
        let leak = Vec3::new(0.9, 0.0, -0.1).normalize();
        assert!(sf.to_local(leak).z > 0.0 && !sf.reflects(wo, leak));
        let lambert = Bsdf::Lambertian { rho: COLOUR };
        let metal = Bsdf::RoughConductor {
            alpha: 0.5,
            tint: COLOUR,
        };
        for bsdf in [lambert, metal] {
            let local = bsdf.eval(sf.to_local(wo), sf.to_local(leak));
            assert!(local.max_element() > 0.0, "the shading frame alone leaks");
            assert_eq!(sf.eval_world(&bsdf, wo, leak), (Vec3::ZERO, 0.0));
        }
        let (f, pdf) = sf.eval_world(&lambert, wo, Vec3::Z);
        assert!(close3(f, COLOUR / std::f32::consts::PI, 1e-6));
        assert!(close(pdf, ns.z / std::f32::consts::PI, 1e-5));
        // Above the geometric surface, below the shading one: zero as well.
        let shadowed = Vec3::new(-0.95, 0.0, 0.2).normalize();
        assert!(sf.reflects(wo, shadowed) && sf.to_local(shadowed).z < 0.0);
        assert_eq!(sf.eval_world(&lambert, wo, shadowed), (Vec3::ZERO, 0.0));

        let mut rng = Rng::new(4);
        let mut refused = 0;
        for _ in 0..10_000 {
            let uc = rng.next_f32();
            match sf.sample_world(&lambert, wo, uc, u2(&mut rng)) {
                None => refused += 1,
                Some(s) => {
                    assert!(s.wi.z > 0.0 && sf.reflects(wo, s.wi), "{}", s.wi);
                    let (_, pdf) = sf.eval_world(&lambert, wo, s.wi);
                    assert!(close(s.pdf, pdf, 1e-4));
                }
            }
        }
        // Cosine-weighted directions project to points uniform on the unit disk around n_s
        // (Malley). The geometric plane, tilted β = 26.57° from it, projects to half an
        // ellipse with semi-axes 1 and cos β, so the share below it is half the disk less half
        // the ellipse: (1 − cos β)/2 = 0.052786, 528 of 10,000 (binomial sd 22; 4.5 sd).
        assert!((428..628).contains(&refused), "{refused}");

        let mirror = Bsdf::Mirror { tint: COLOUR };
        let grazing = dir(60f32.to_radians(), std::f32::consts::PI);
        let sf = ShadingFrame::new(ns, ng, grazing);
        let r = sf.to_world(reflect_local(sf.to_local(grazing)));
        assert!(r.z < 0.0, "the shading reflection goes below: {r}");
        assert_eq!(sf.sample_world(&mirror, grazing, 0.5, Vec2::ZERO), None);
        let s = ShadingFrame::new(ng, ng, grazing)
            .sample_world(&mirror, grazing, 0.5, Vec2::ZERO)
            .unwrap();
        assert!((s.wi - reflect(-grazing, ng)).length() < 1e-6);
    }

    /// Glass through a [`ShadingFrame`] with its normal pointing out: from outside it bends
    /// towards the normal (sin θ_t = sin θ_i/1.5) into the other geometric side, from inside
    /// ([`ShadingFrame::front_face`] false, η inverted) away from it (sin θ_t = 1.5 sin θ_i),
    /// out. With a tilted shading normal, over wo on both sides and 200 `uc` each, every
    /// reflection (weight 1) stays on wo's geometric side and every refraction (weight tint)
    /// crosses the geometric surface.
    #[test]
    fn glass_through_a_shading_frame_crosses_the_geometric_surface() {
        let tint = Vec3::new(0.5, 0.7, 0.9);
        let glass = Bsdf::Glass { ior: 1.5, tint };
        let ng = Vec3::Z;
        let outside = dir(40f32.to_radians(), 0.3);
        let sf = ShadingFrame::new(ng, ng, outside);
        assert!(sf.front_face());
        let t = sf.sample_world(&glass, outside, 0.999, Vec2::ZERO).unwrap();
        assert!(t.wi.z < 0.0 && t.weight == tint);
        let sin_t = t.wi.truncate().length();
        assert!(
            (sin_t - 40f32.to_radians().sin() / 1.5).abs() < 1e-5,
            "{}",
            t.wi
        );
        let f = fresnel_dielectric(40f32.to_radians().cos(), 1.5);
        assert!((t.pdf - (1.0 - f)).abs() < 1e-6);
        let r = sf.sample_world(&glass, outside, 0.0, Vec2::ZERO).unwrap();
        assert!((r.wi - reflect(-outside, ng)).length() < 1e-6 && r.weight == Vec3::ONE);

        let inside = flip_z(dir(30f32.to_radians(), 0.3));
        let sf = ShadingFrame::new(ng, ng, inside);
        assert!(!sf.front_face());
        let t = sf.sample_world(&glass, inside, 0.999, Vec2::ZERO).unwrap();
        assert!(t.wi.z > 0.0 && t.weight == tint, "leaves: {}", t.wi);
        let sin_t = t.wi.truncate().length();
        assert!((sin_t - 0.75).abs() < 1e-5, "{}", t.wi);
        let f = fresnel_dielectric(30f32.to_radians().cos(), 1.0 / 1.5);
        assert!((t.pdf - (1.0 - f)).abs() < 1e-6);

        let ns = Vec3::new(0.3, 0.0, 1.0).normalize();
        let mut rng = Rng::new(6);
        let (mut reflected, mut refracted) = (0, 0);
        for k in 0..400 {
            let mut wo = uniform_hemisphere(rng.next_f32(), rng.next_f32());
            if k % 2 == 1 {
                wo = flip_z(wo);
            }
            let sf = ShadingFrame::new(ns, ng, wo);
            for i in 0..200 {
                let uc = (i as f32 + 0.5) / 200.0;
                let Some(s) = sf.sample_world(&glass, wo, uc, Vec2::ZERO) else {
                    continue;
                };
                if s.weight == Vec3::ONE {
                    reflected += 1;
                    assert!(sf.reflects(wo, s.wi) && s.wi.dot(wo.z.signum() * ng) > 0.0);
                } else {
                    refracted += 1;
                    assert!(!sf.reflects(wo, s.wi) && s.wi.dot(wo.z.signum() * ng) < 0.0);
                }
            }
        }
        assert!(
            reflected > 5_000 && refracted > 20_000,
            "{reflected} {refracted}"
        );
    }
}
