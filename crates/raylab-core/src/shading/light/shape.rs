//! Which emitter the scene's light is (`emitter`): a point, a sphere, a square or a spot.

use super::{AnyLight, LightKind, LightSpec, PointLight, QuadLight, SphereLight, SpotLight};

/// The scene's light as an emitter, centred on its position, with its total power per channel
/// (`P · colour`); the one place a kind of light becomes its [`Light`]:
///
/// * [`LightKind::Point`]: the lab's [`PointLight`];
/// * [`LightKind::Sphere`]: a [`SphereLight`] of that radius;
/// * [`LightKind::Quad`]: a [`QuadLight`] of that side, facing the floor (+y);
/// * [`LightKind::Spot`]: a [`SpotLight`] with the omni light's intensity `P · colour / (4π)`.
///
/// A sphere or square whose size is not above 0 (or not finite) is the point light: of no
/// size, its radiance would be infinite.
pub fn emitter(light: &LightSpec) -> AnyLight {
    let (centre, power) = (light.position, light.channel_power());
    let point = AnyLight::Point(PointLight {
        position: centre,
        power,
    });
    let sized = |size: f32| size > 0.0 && size < f32::INFINITY;
    match light.kind {
        LightKind::Point => point,
        LightKind::Sphere { radius } if sized(radius) => AnyLight::Sphere(SphereLight {
            centre,
            radius,
            power,
        }),
        LightKind::Quad { side } if sized(side) => AnyLight::Quad(QuadLight {
            centre,
            side,
            power,
        }),
        LightKind::Sphere { .. } | LightKind::Quad { .. } => point,
        LightKind::Spot(cone) => AnyLight::Spot(SpotLight::new(centre, power, cone)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::geometry::Ray;
    use crate::base::sampling::Rng;
    use crate::shading::light::Light;
    use crate::shading::light::{LightShape, SpotCone};
    use glam::{Vec2, Vec3};

    #[test]
    fn light_shapes_by_name() {
        assert_eq!(LightShape::default(), LightShape::Point);
        for shape in LightShape::ALL {
            assert_eq!(shape.name().parse::<LightShape>(), Ok(shape));
            assert_eq!(shape.to_string(), shape.name());
            let json = serde_json::to_string(&shape).unwrap();
            assert_eq!(json, format!("\"{}\"", shape.name()));
            assert_eq!(serde_json::from_str::<LightShape>(&json).unwrap(), shape);
        }
        assert!("disk".parse::<LightShape>().unwrap_err().contains("disk"));
        assert!(serde_json::from_str::<LightShape>("\"Sphere\"").is_err());
    }

    /// The lab's light of kind `shape`, with `size` for a sphere's radius or a square's side.
    fn lab_of(shape: LightShape, size: f32) -> LightSpec {
        LightSpec {
            colour: Vec3::new(1.0, 0.5, 0.25),
            kind: LightKind::sized(shape, size),
            ..LightSpec::default()
        }
    }

    /// `emitter` centres each kind on the lab's light with its power per channel; a sphere or
    /// square of no size gives the point light.
    #[test]
    fn emitter_makes_each_kind_from_the_labs_light() {
        let power = Vec3::new(14.0, 7.0, 3.5);
        let lab = lab_of(LightShape::Point, 0.0);
        let point = AnyLight::Point(PointLight {
            position: lab.position,
            power,
        });
        assert_eq!(emitter(&lab_of(LightShape::Point, 0.2)), point);
        assert_eq!(
            emitter(&lab_of(LightShape::Sphere, 0.2)),
            AnyLight::Sphere(SphereLight {
                centre: lab.position,
                radius: 0.2,
                power
            })
        );
        assert_eq!(
            emitter(&lab_of(LightShape::Quad, 0.5)),
            AnyLight::Quad(QuadLight {
                centre: lab.position,
                side: 0.5,
                power
            })
        );
        let spot = emitter(&lab_of(LightShape::Spot, 0.0));
        assert_eq!(
            spot,
            AnyLight::Spot(SpotLight::new(lab.position, power, SpotCone::default()))
        );
        for shape in [LightShape::Point, LightShape::Sphere, LightShape::Quad] {
            assert_eq!(emitter(&lab_of(shape, 0.2)).power(), power);
            for size in [0.0, -1.0, f32::NAN, f32::INFINITY] {
                assert_eq!(emitter(&lab_of(shape, size)), point);
            }
        }
        assert!(emitter(&lab_of(LightShape::Point, 0.2)).is_delta());
        assert!(!emitter(&lab_of(LightShape::Sphere, 0.2)).is_delta());
        assert!(!emitter(&lab_of(LightShape::Quad, 0.2)).is_delta());
        assert!(spot.is_delta());
    }

    /// `AnyLight` answers exactly as the light inside it, and the interface is object safe
    /// (the lights can be held as `Box<dyn Light + Send + Sync>` too).
    #[test]
    fn any_light_answers_as_the_light_inside() {
        let mut rng = Rng::new(17);
        for shape in LightShape::ALL {
            let any = emitter(&lab_of(shape, 0.3));
            let inner: Box<dyn Light + Send + Sync> = match any {
                AnyLight::Point(l) => Box::new(l),
                AnyLight::Sphere(l) => Box::new(l),
                AnyLight::Quad(l) => Box::new(l),
                AnyLight::Spot(l) => Box::new(l),
            };
            for _ in 0..200 {
                let p = Vec3::new(
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                );
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                let s = any.sample_li(p, u);
                assert_eq!(s, inner.sample_li(p, u));
                let wi = s.map_or(Vec3::X, |s| s.wi);
                assert_eq!(any.pdf_li(p, wi), inner.pdf_li(p, wi));
                let ray = Ray {
                    origin: p,
                    direction: wi,
                };
                assert_eq!(any.intersect(&ray, 5.0), inner.intersect(&ray, 5.0));
                assert_eq!(any.le(wi), inner.le(wi));
                assert_eq!(any.sample_le(u, 1.0 - u), inner.sample_le(u, 1.0 - u));
            }
            assert_eq!(any.is_delta(), inner.is_delta());
            assert_eq!(any.power(), inner.power());
        }
    }

    /// Photon rays leave each light as it emits: from the point itself in every direction
    /// alike (their mean direction near 0); from the sphere's surface, outward, with the
    /// cosine about its normal averaging 2/3 (cosine-weighted: E[cos θ] = 2/3); from the
    /// square, inside it and toward +y only, E[cos θ] = 2/3 too. Unit directions throughout.
    #[test]
    fn photon_rays_leave_each_light_as_it_emits() {
        let lab = LightSpec::default();
        let n = 40_000;
        for shape in LightShape::ALL {
            let light = emitter(&lab_of(shape, 0.25));
            let mut rng = Rng::new(3);
            let (mut mean_direction, mut mean_cos) = (Vec3::ZERO, 0.0f64);
            for _ in 0..n {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                let v = Vec2::new(rng.next_f32(), rng.next_f32());
                let ray = light.sample_le(u, v).unwrap();
                assert!((ray.direction.length() - 1.0).abs() < 1e-5);
                mean_direction += ray.direction / n as f32;
                let cos = match shape {
                    LightShape::Point | LightShape::Spot => {
                        assert_eq!(ray.origin, lab.position);
                        continue;
                    }
                    LightShape::Sphere => {
                        let normal = (ray.origin - lab.position) / 0.25;
                        assert!((normal.length() - 1.0).abs() < 1e-5);
                        ray.direction.dot(normal)
                    }
                    LightShape::Quad => {
                        let d = ray.origin - lab.position;
                        assert!(
                            d.y == 0.0 && d.x.abs() <= 0.125 && d.z.abs() <= 0.125,
                            "{d}"
                        );
                        ray.direction.y
                    }
                };
                assert!(cos >= 0.0, "{cos}");
                mean_cos += f64::from(cos) / f64::from(n);
            }
            match shape {
                LightShape::Point => assert!(mean_direction.length() < 0.02, "{mean_direction}"),
                // The spot's photons: its own test (`spot::tests`) checks their angles.
                LightShape::Spot => assert!(mean_direction.dot(Vec3::Y) > 0.9),
                LightShape::Sphere | LightShape::Quad => {
                    assert!((mean_cos - 2.0 / 3.0).abs() < 0.005, "{shape}: {mean_cos}")
                }
            }
        }
        let nowhere = PointLight {
            position: Vec3::NAN,
            power: Vec3::ONE,
        };
        assert_eq!(nowhere.sample_le(Vec2::ZERO, Vec2::ZERO), None);
    }
}
