//! Display transforms: how linear image values become the 8-bit pixels on screen and in PNGs.
//!
//! Applied for display only: the film keeps linear values, EXR files keep them too (before
//! exposure and curve), and changing the transform never re-traces.
//!
//! A [`Display`] is an exposure (in stops) and a [`DisplayTransform`]: the lab's (clamp, no
//! gamma: the default, so the lab's figures look as in the lab), sRGB, or a filmic curve. The
//! lab's transform is [`to_display_u8`] itself. The other two are defined by
//! [`srgb_encode`] and [`aces_filmic`], evaluated in `f64`; to keep a 16-megapixel image cheap
//! they are not evaluated per pixel: the 255 exposed values where the 8-bit code steps up are
//! found once from those definitions, and a table indexed by a value's top bits finds its step
//! in one look-up. So the table gives exactly what the formulas give (tests compare them at
//! every step and over a sweep of `f32` values; an ignored one, for every `f32` up to 8).
//! Whole images are converted in parallel (rayon), in the pool of whoever calls.

use std::sync::OnceLock;

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::base::named::named_enum;

/// The lab's display: clamp to [0, 1], scale to 255, round (halves up). NaN shows as 0.
#[allow(clippy::manual_clamp)]
#[inline]
pub fn to_display_u8(linear: f32) -> u8 {
    // `clamp` passes NaN through; `max` first turns it into 0.
    let v = linear.max(0.0).min(1.0) * 255.0;
    // `v.round()`, without the call into the maths library it is on x86-64 (a third of the time
    // of a whole image): v is in [0, 255], so its whole part and `v − whole` are exact, and a
    // fraction of at least ½ rounds up, as `round` does.
    let whole = v as u8;
    whole + u8::from(v - f32::from(whole) >= 0.5)
}

/// The curve that maps an exposed linear value to a display value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DisplayTransform {
    /// The lab's display: each channel clamped to [0, 1], no gamma. The default.
    #[default]
    Lab,
    /// The standard sRGB encoding ([`srgb_encode`]) of the value clamped to [0, 1].
    Srgb,
    /// A filmic curve ([`aces_filmic`]: highlights roll off to white instead of clipping), then
    /// the sRGB encoding.
    Filmic,
}

named_enum!(DisplayTransform as "display" {
    Lab => "lab", "Lab (clamp, no gamma)";
    Srgb => "srgb", "sRGB";
    Filmic => "filmic", "Filmic (ACES fit)";
});

/// A display transform and the exposure before it.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Display {
    pub transform: DisplayTransform,
    /// Exposure in stops: linear values are multiplied by 2^exposure before the curve.
    pub exposure: f32,
}

impl Display {
    /// The linear value after exposure: `linear · 2^exposure`.
    pub fn exposed(&self, linear: Vec3) -> Vec3 {
        linear * self.scale()
    }

    /// The factor `2^exposure` (exactly 1 at 0 EV, so the lab's default display is unchanged).
    fn scale(&self) -> f32 {
        self.exposure.exp2()
    }

    /// One pixel as 8-bit RGB: exposed, then each channel through the transform's curve.
    pub fn encode(&self, linear: Vec3) -> [u8; 3] {
        let curve = self.transform.curve();
        self.exposed(linear).to_array().map(|v| curve.encode(v))
    }

    /// One channel as 8 bits: `linear · 2^exposure` through the transform's curve.
    pub fn encode_channel(&self, linear: f32) -> u8 {
        self.transform.curve().encode(linear * self.scale())
    }

    /// A whole image's pixels as 8-bit RGB, rows in parallel: the same bytes as [`Display::encode`] per
    /// pixel.
    pub fn to_rgb8(&self, pixels: &[Vec3]) -> Vec<u8> {
        self.convert::<3>(pixels)
    }

    /// A whole image's pixels as 8-bit RGBA with opaque alpha (what textures take), in parallel: the same
    /// bytes as [`Display::encode`] per pixel, then 255.
    pub fn to_rgba8(&self, pixels: &[Vec3]) -> Vec<u8> {
        self.convert::<4>(pixels)
    }

    /// Some pixels (rows of an image, say) as 8-bit RGB into `out` (three bytes a pixel), in
    /// parallel: the bytes [`Display::to_rgb8`] gives them. What a PNG is written from, a band
    /// of rows at a time, without an 8-bit copy of the whole image.
    pub fn rgb8_into(&self, pixels: &[Vec3], out: &mut [u8]) {
        self.convert_into::<3>(pixels, out);
    }

    fn convert<const N: usize>(&self, pixels: &[Vec3]) -> Vec<u8> {
        let mut out = vec![0u8; pixels.len() * N];
        self.convert_into::<N>(pixels, &mut out);
        out
    }

    /// The curve chosen once, outside the loop, so each loop is compiled for one curve.
    fn convert_into<const N: usize>(&self, pixels: &[Vec3], out: &mut [u8]) {
        let scale = self.scale();
        match self.transform.curve() {
            Curve::Lab => convert::<N>(pixels, out, |v| to_display_u8(v * scale)),
            Curve::Table(steps) => convert::<N>(pixels, out, |v| steps.encode(v * scale)),
        }
    }
}

impl DisplayTransform {
    /// The curve on an already exposed value, as 8 bits.
    pub fn encode_exposed(self, exposed: f32) -> u8 {
        self.curve().encode(exposed)
    }

    fn curve(self) -> Curve {
        static SRGB: OnceLock<Steps> = OnceLock::new();
        static FILMIC: OnceLock<Steps> = OnceLock::new();
        match self {
            DisplayTransform::Lab => Curve::Lab,
            DisplayTransform::Srgb => Curve::Table(SRGB.get_or_init(|| Steps::find(self))),
            DisplayTransform::Filmic => Curve::Table(FILMIC.get_or_init(|| Steps::find(self))),
        }
    }
}

/// The sRGB encoding (IEC 61966-2-1) of a linear value in [0, 1]: a straight segment near black,
/// `12.92·c` for `c ≤ 0.0031308`, else `1.055·c^(1/2.4) − 0.055`.
pub fn srgb_encode(c: f64) -> f64 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The filmic tone curve: Krzysztof Narkowicz's fit of the ACES filmic curve ("ACES Filmic Tone
/// Mapping Curve", 2016),
///
/// f(x) = clamp(x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14), 0, 1),
///
/// for a linear value `x ≥ 0` (negative values, which the tracer never makes, are taken as 0:
/// the rational function is not meant for them). It is a fit of the curve only (no ACES colour
/// space conversion), applied to each channel on its own, so very bright colours drift towards
/// white. Its toe darkens the shadows a little, and highlights roll off to white instead of
/// clipping: f(1) = 2.54/3.16 = 0.8038, and f reaches 1 only at x ≈ 7.24 (where
/// 0.08x² − 0.56x − 0.14 = 0), so values a few stops above 1 still differ on screen.
pub fn aces_filmic(x: f64) -> f64 {
    // +∞ would make ∞/∞; every x above 7.24 gives 1 anyway.
    let x = x.clamp(0.0, f64::from(f32::MAX));
    (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// The definition of the sRGB and filmic displays on an exposed value: the curve in `f64`,
/// times 255, rounded. NaN, negative values and zero give 0.
fn reference_u8(transform: DisplayTransform, exposed: f32) -> u8 {
    if !(exposed > 0.0) {
        return 0;
    }
    let x = f64::from(exposed);
    let display = match transform {
        DisplayTransform::Lab => return to_display_u8(exposed),
        DisplayTransform::Srgb => srgb_encode(x.min(1.0)),
        DisplayTransform::Filmic => srgb_encode(aces_filmic(x)),
    };
    (display * 255.0).round() as u8
}

#[derive(Clone, Copy)]
enum Curve {
    Lab,
    Table(&'static Steps),
}

impl Curve {
    #[inline]
    fn encode(self, exposed: f32) -> u8 {
        match self {
            Curve::Lab => to_display_u8(exposed),
            Curve::Table(steps) => steps.encode(exposed),
        }
    }
}

/// For a curve whose 8-bit code never decreases as the value grows (sRGB, filmic then sRGB), the
/// exposed values where the code steps up, and a table that finds the step below a value in one
/// look-up instead of a `powf`.
struct Steps {
    /// `next[k]`: the value where the code leaves `k`, the smallest exposed value whose code is
    /// `k + 1` or more (NaN after 255: no value passes it).
    next: [f32; 256],
    /// The code at the start of each bucket of values that share their top 16 bits (the
    /// exponent and 7 bits of mantissa: 128 buckets an octave). No bucket holds more than one
    /// step ([`Steps::find`] checks), so the code is the bucket's, or one more past `next`.
    bucket: Box<[u8; BUCKETS]>,
}

/// `f32` values by their top 16 bits, the sign left out: non-negative values up to +∞ (0x7f80),
/// then NaNs, which [`Steps::encode`] never looks up (their entries are 0).
const BUCKETS: usize = 1 << 15;

impl Steps {
    /// Each step by bisection over the non-negative `f32` values (their bit patterns are in the
    /// same order as the values), from [`reference_u8`]: 255 × 31 evaluations, once.
    fn find(transform: DisplayTransform) -> Self {
        let mut steps = [f32::NEG_INFINITY; 256];
        for (k, step) in steps.iter_mut().enumerate().skip(1) {
            let (mut lo, mut hi) = (0u32, f32::INFINITY.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if usize::from(reference_u8(transform, f32::from_bits(mid))) >= k {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *step = f32::from_bits(lo);
        }
        // −0.0 ≤ +0.0: a first step at zero would show −0.0 brighter than black.
        assert!(steps[1] > 0.0);
        let mut next = [f32::NAN; 256];
        next[..255].copy_from_slice(&steps[1..]);
        let code = |v: f32| steps[1..].iter().take_while(|&&s| s <= v).count();
        let mut bucket = Box::new([0u8; BUCKETS]);
        for (i, b) in bucket.iter_mut().enumerate() {
            let first = f32::from_bits((i as u32) << 16);
            let last = f32::from_bits(((i as u32) << 16) | 0xffff);
            // +∞'s bucket holds NaNs after it; they count as nothing.
            let last = if last.is_nan() { first } else { last };
            let (low, high) = (code(first), code(last));
            assert!(high <= low + 1, "{transform}: two steps in bucket {i:#x}");
            *b = low as u8;
        }
        Self { next, bucket }
    }

    /// The code of an exposed value. NaN and negative values are black: `max` makes them 0
    /// (perhaps −0.0, whose sign bit the mask drops), so the index never leaves the table.
    #[inline]
    fn encode(&self, exposed: f32) -> u8 {
        let v = exposed.max(0.0);
        let code = self.bucket[((v.to_bits() >> 16) & 0x7fff) as usize];
        code + u8::from(v >= self.next[usize::from(code)])
    }
}

/// Pixels per parallel task: large enough that scheduling is noise, small enough to spread a
/// 1-megapixel image over many threads.
const CHUNK: usize = 16 * 1024;

/// Each pixel's three channels through `channel`, plus opaque alpha when `N` is 4, into `out`
/// (`N` bytes a pixel).
fn convert<const N: usize>(pixels: &[Vec3], out: &mut [u8], channel: impl Fn(f32) -> u8 + Sync) {
    assert_eq!(out.len(), pixels.len() * N);
    pixels
        .par_chunks(CHUNK)
        .zip(out.par_chunks_mut(CHUNK * N))
        .for_each(|(pixels, out)| {
            for (p, o) in pixels.iter().zip(out.as_chunks_mut::<N>().0) {
                let mut pixel = [255; N];
                pixel[0] = channel(p.x);
                pixel[1] = channel(p.y);
                pixel[2] = channel(p.z);
                *o = pixel;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::film::Image;

    fn display(transform: DisplayTransform, exposure: f32) -> Display {
        Display {
            transform,
            exposure,
        }
    }

    const LAB: Display = Display {
        transform: DisplayTransform::Lab,
        exposure: 0.0,
    };

    /// Values a display meets: ordinary ones, the edges, and what a broken pixel holds.
    const SWEEP: [f32; 16] = [
        0.0,
        -0.0,
        1e-6,
        0.0031308,
        0.15,
        0.18,
        0.25,
        0.5,
        0.75,
        1.0,
        7.5,
        1e6,
        -2.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];

    #[test]
    fn exposure_is_in_stops() {
        // +1 EV doubles, −2 EV quarters, 0 EV leaves the value as it is.
        let v = Vec3::new(0.25, 1.0, 3.0);
        assert_eq!(display(DisplayTransform::Lab, 1.0).exposed(v), 2.0 * v);
        assert_eq!(display(DisplayTransform::Srgb, -2.0).exposed(v), 0.25 * v);
        assert_eq!(LAB.exposed(v), v);
        // Lab at +1 EV: 0.25 → 0.5 → 0.5 · 255 = 127.5 → 128; 0.75 → 1.5, clamped → 255.
        let plus_one = display(DisplayTransform::Lab, 1.0);
        assert_eq!(plus_one.encode(Vec3::new(0.25, 0.75, 0.0)), [128, 255, 0]);
        assert_eq!(plus_one.encode_channel(0.25), 128);
    }

    #[test]
    fn lab_at_0_ev_is_the_labs_display() {
        for v in SWEEP {
            assert_eq!(LAB.encode_channel(v), to_display_u8(v), "{v}");
            assert_eq!(LAB.encode(Vec3::splat(v)), [to_display_u8(v); 3], "{v}");
        }
        let image = Image {
            width: 4,
            height: 4,
            pixels: SWEEP.iter().map(|&v| Vec3::new(v, 0.5, -v)).collect(),
        };
        let old: Vec<u8> = image
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(to_display_u8))
            .collect();
        assert_eq!(LAB.to_rgb8(&image.pixels), old);
    }

    /// By hand: 0.5 → 1.055 · 0.5^(1/2.4) − 0.055 = 0.735357 → · 255 = 187.516 → 188;
    /// 0.18 → 1.055 · 0.18^(1/2.4) − 0.055 = 0.461356 → 117.646 → 118 (the lab's display shows
    /// 0.18 as 46).
    #[test]
    fn srgb_by_hand() {
        let srgb = display(DisplayTransform::Srgb, 0.0);
        assert_eq!(srgb.encode_channel(0.0), 0);
        assert_eq!(srgb.encode_channel(1.0), 255);
        assert_eq!(srgb.encode_channel(0.5), 188);
        assert_eq!(srgb.encode_channel(0.18), 118);
        assert!((srgb_encode(0.5) - 0.735357).abs() < 1e-6);
        // At the boundary both pieces give 0.040450 (12.92 · 0.0031308), · 255 = 10.31 → 10.
        assert!((srgb_encode(0.0031308) - 0.0404499).abs() < 1e-7);
        assert!((srgb_encode(0.003131) - 0.0404525).abs() < 1e-7);
        assert_eq!(srgb.encode_channel(0.0031308), 10);
        assert_eq!(srgb.encode_channel(0.003131), 10);
        // Below it, a straight line: 0.001 → 0.01292 · 255 = 3.29 → 3.
        assert_eq!(srgb.encode_channel(0.001), 3);
        // Clamped: above 1 is white; negative, NaN and −∞ are black.
        for (v, code) in [
            (7.5, 255),
            (f32::INFINITY, 255),
            (-2.0, 0),
            (-0.0, 0),
            (f32::NAN, 0),
            (f32::NEG_INFINITY, 0),
        ] {
            assert_eq!(srgb.encode_channel(v), code, "{v}");
        }
        // Exposure first: 0.25 at +1 EV is 0.5 → 188.
        assert_eq!(
            display(DisplayTransform::Srgb, 1.0).encode_channel(0.25),
            188
        );
    }

    /// By hand: f(1) = 2.54 / 3.16 = 0.803797; sRGB: 1.055 · 0.803797^(1/2.4) − 0.055 =
    /// 0.908230 → · 255 = 231.60 → 232. f(0.18) = 0.05130 / 0.19221 = 0.266899 → 0.553458 →
    /// 141.13 → 141.
    #[test]
    fn filmic_by_hand() {
        assert!((aces_filmic(1.0) - 2.54 / 3.16).abs() < 1e-12);
        assert!((aces_filmic(0.18) - 0.266899).abs() < 1e-6);
        let filmic = display(DisplayTransform::Filmic, 0.0);
        assert_eq!(filmic.encode_channel(1.0), 232);
        assert_eq!(filmic.encode_channel(0.18), 141);
        assert_eq!(filmic.encode_channel(0.0), 0);
        assert_eq!(filmic.encode_channel(1e6), 255);
        assert_eq!(filmic.encode_channel(f32::INFINITY), 255);
        assert_eq!(filmic.encode_channel(f32::NAN), 0);
        assert_eq!(filmic.encode_channel(-2.0), 0);
        // Rolls off: 1 is not white yet, and 2 is brighter still (f(2) = 10.16/11.1 → 245).
        assert_eq!(filmic.encode_channel(2.0), 245);
        // Monotonic over a sweep from 10⁻⁴ to 10⁴.
        let codes: Vec<u8> = (0..=800)
            .map(|i| filmic.encode_channel(10f32.powf(-4.0 + i as f32 / 100.0)))
            .collect();
        assert!(codes.windows(2).all(|w| w[0] <= w[1]), "{codes:?}");
        assert_eq!((codes[0], codes[800]), (0, 255));
    }

    /// The tables give exactly what the formulas give: at every step and just below it, and over
    /// a sweep of `f32` bit patterns across the whole range.
    #[test]
    fn tables_equal_the_formulas() {
        for transform in [DisplayTransform::Srgb, DisplayTransform::Filmic] {
            let Curve::Table(steps) = transform.curve() else {
                unreachable!()
            };
            for k in 1..=255usize {
                let step = steps.next[k - 1];
                let below = f32::from_bits(step.to_bits() - 1);
                assert_eq!(usize::from(steps.encode(step)), k, "{transform} step {k}");
                assert_eq!(usize::from(reference_u8(transform, step)), k);
                assert_eq!(usize::from(steps.encode(below)), k - 1);
                assert_eq!(usize::from(reference_u8(transform, below)), k - 1);
            }
            for bits in (0..=u32::MAX).step_by(8191) {
                let v = f32::from_bits(bits);
                assert_eq!(
                    transform.encode_exposed(v),
                    reference_u8(transform, v),
                    "{transform} {v}"
                );
            }
        }
    }

    /// Every non-negative `f32` up to 8 (past the last step of both curves), in parallel: about
    /// 1.1 billion values, some seconds in release. `cargo test --release -- --ignored
    /// every_value`.
    #[test]
    #[ignore]
    fn tables_equal_the_formulas_for_every_value() {
        for transform in [DisplayTransform::Srgb, DisplayTransform::Filmic] {
            let mismatches = (0..=8f32.to_bits())
                .into_par_iter()
                .filter(|&bits| {
                    let v = f32::from_bits(bits);
                    transform.encode_exposed(v) != reference_u8(transform, v)
                })
                .count();
            assert_eq!(mismatches, 0, "{transform}");
        }
    }

    #[test]
    fn whole_images_equal_the_per_pixel_function() {
        // Enough pixels for several parallel chunks, with a ragged last one.
        let (width, height) = (301, 123);
        let pixels = (0..width * height)
            .map(|i| {
                let t = i as f32 / (width * height) as f32;
                Vec3::new(t * 4.0 - 0.5, (t * 37.0).fract(), 1.0 / (t + 1e-3))
            })
            .chain(SWEEP.iter().map(|&v| Vec3::splat(v)))
            .collect::<Vec<_>>();
        let image = Image {
            width: pixels.len() as u32,
            height: 1,
            pixels,
        };
        for transform in DisplayTransform::ALL {
            for exposure in [-1.5, 0.0, 2.0] {
                let d = display(transform, exposure);
                let rgb: Vec<u8> = image.pixels.iter().flat_map(|&p| d.encode(p)).collect();
                let rgba: Vec<u8> = image
                    .pixels
                    .iter()
                    .flat_map(|&p| {
                        let [r, g, b] = d.encode(p);
                        [r, g, b, 255]
                    })
                    .collect();
                assert_eq!(d.to_rgb8(&image.pixels), rgb, "{transform} {exposure}");
                assert_eq!(d.to_rgba8(&image.pixels), rgba, "{transform} {exposure}");
            }
        }
    }

    #[test]
    fn names_round_trip() {
        for t in DisplayTransform::ALL {
            assert_eq!(t.name().parse::<DisplayTransform>(), Ok(t));
            assert_eq!(t.to_string(), t.name());
        }
        assert!(
            "gamma"
                .parse::<DisplayTransform>()
                .unwrap_err()
                .contains("gamma")
        );
    }

    #[test]
    fn serde_round_trip() {
        let d = display(DisplayTransform::Filmic, -1.5);
        let json = serde_json::to_string(&d).unwrap();
        assert_eq!(json, r#"{"transform":"filmic","exposure":-1.5}"#);
        assert_eq!(serde_json::from_str::<Display>(&json).unwrap(), d);
        // Missing fields take their defaults: the lab's display at 0 EV.
        assert_eq!(
            serde_json::from_str::<Display>("{}").unwrap(),
            Display::default()
        );
        assert_eq!(Display::default(), LAB);
    }
}
