//! A global factor: the exact figure times a constant in each channel, the look of a wrong
//! light power P, a constant factor left in or out, or an exposure.
//!
//! The factor is fitted by least squares in linear light, channel by channel: the student's
//! value k/255 against the exact figure's linear value L (before the display clamps it), over
//! the pixels the student's image does not clip at 255 (there the value says only "at least
//! 1"). The figure times the factor, through the lab's display, is then compared as any
//! mistake's figure is: how much of the image it explains.

use glam::Vec3;
use serde::Serialize;

use super::compare::Rgb8;
use crate::transport::film::Image;

/// A factor and the share of pixels the figure times it explains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FactorCandidate {
    /// The factor in each channel, R, G, B.
    pub factor: [f64; 3],
    pub explains: f64,
}

/// Factors closer than this to each other are one factor "everywhere"; closer than this to 1,
/// no factor.
const SAME: f64 = 0.01;

/// The factor in each channel that best maps the exact figure (`linear`) onto `image`, or
/// `None` when a channel has no unclipped light to fit.
pub fn fit(image: &Rgb8, linear: &Image) -> Option<Vec3> {
    let mut sums = [(0.0f64, 0.0f64); 3];
    for (p, l) in image.data.chunks_exact(3).zip(&linear.pixels) {
        for c in 0..3 {
            let (s, l) = (p[c], f64::from(l[c]));
            if s < 255 && l.is_finite() {
                sums[c].0 += f64::from(s) / 255.0 * l;
                sums[c].1 += l * l;
            }
        }
    }
    let k = sums.map(|(sl, ll)| (ll > 0.0).then(|| sl / ll));
    match k {
        [Some(r), Some(g), Some(b)] if [r, g, b].iter().all(|k| k.is_finite()) => {
            Some(Vec3::new(r as f32, g as f32, b as f32))
        }
        _ => None,
    }
}

/// The exact figure times `factor`, through the lab's display.
pub fn scaled(linear: &Image, factor: Vec3) -> Rgb8 {
    Rgb8::from_linear(&Image {
        pixels: linear.pixels.iter().map(|p| *p * factor).collect(),
        ..linear.clone()
    })
}

/// The factor as a person reads it: "× 0.60 everywhere", or per channel.
pub fn describe(factor: [f64; 3]) -> String {
    let [r, g, b] = factor;
    if (r - g).abs() <= SAME && (g - b).abs() <= SAME && (r - b).abs() <= SAME {
        format!("× {:.2} everywhere", (r + g + b) / 3.0)
    } else {
        format!("× ({r:.2}, {g:.2}, {b:.2}) in R, G, B")
    }
}

/// How to look for it, in a sentence.
pub fn fix(factor: [f64; 3]) -> String {
    let [r, g, b] = factor;
    let one = (r - g).abs() <= SAME && (g - b).abs() <= SAME && (r - b).abs() <= SAME;
    let what = if one {
        "a wrong light power P, or a constant factor left in or out (4π, π, 255, an exposure)"
    } else {
        "a wrong light colour or power P per channel, or a constant factor on some channels"
    };
    format!(
        "Your image is the exact figure {}: check {what}; print D at one pixel and compare it \
         with raylab inspect.",
        describe(factor)
    )
}

/// The lab's equation a factor concerns.
pub const EQUATION: &str =
    "equation 27: D = P·max(r̂·n̂, 0)/(4πr²), P the light's power (and R written as it is, × 255)";

#[cfg(test)]
mod tests {
    use super::*;

    /// The figure × 0.6, rounded to 8 bits, gives back 0.6 within rounding; a figure × 1.5 whose
    /// bright pixels clip at 255 gives back 1.5, the clipped pixels left out.
    #[test]
    fn a_factor_is_fitted_through_rounding_and_clipping() {
        let linear = Image {
            width: 4,
            height: 1,
            pixels: vec![
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(0.5, 0.6, 0.05),
                Vec3::new(0.9, 0.8, 0.7),
                Vec3::new(0.02, 0.4, 0.65),
            ],
        };
        for k in [0.6f32, 1.5] {
            let image = scaled(&linear, Vec3::splat(k));
            let got = fit(&image, &linear).unwrap();
            assert!(
                (got - Vec3::splat(k)).abs().max_element() < 0.01,
                "{k}: {got}"
            );
            assert_eq!(scaled(&linear, got), image);
        }
        assert_eq!(describe([0.6, 0.6, 0.601]), "× 0.60 everywhere");
        assert_eq!(describe([0.6, 0.5, 0.6]), "× (0.60, 0.50, 0.60) in R, G, B");
    }
}
