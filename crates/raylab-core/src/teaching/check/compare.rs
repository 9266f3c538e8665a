//! How far one 8-bit image is from another: the share of pixels within a tolerance, the worst
//! block, the difference picture, and the share that anti-aliasing explains.
//!
//! Every number here is on 8-bit values (0 to 255 a channel), the values a PNG or an SDL
//! screenshot holds: the student's image is compared with the figure exactly as `raylab render`
//! writes it (the lab's display, [`crate::transport::display::to_display_u8`]).

use rayon::prelude::*;
use serde::Serialize;

use crate::transport::film::Image;

/// How far a channel may be from the figure's and still count as the same: 2 of 255. A student
/// who rounds where raylab rounds (or truncates, or computes in `double`) lands within 1; 2
/// leaves room for both.
pub const TOLERANCE: u8 = 2;

/// The side of the square blocks the worst region is looked for in, in pixels.
pub const BLOCK: u32 = 32;

/// How much the difference picture amplifies |A − B|: a difference of 2/255, at the edge of the
/// tolerance, shows as 16/255; one of 32/255 or more is white.
pub const DIFF_GAIN: u32 = 8;

/// An 8-bit RGB image, rows top to bottom, three bytes a pixel: a student's render, or a figure
/// as the lab displays it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rgb8 {
    pub width: u32,
    pub height: u32,
    /// `width × height × 3` bytes: R, G, B of each pixel in turn.
    pub data: Vec<u8>,
}

impl Rgb8 {
    /// A linear image through the lab's display (clamp, × 255, round; no gamma): exactly the
    /// pixels of the PNG `raylab render` writes ([`Image::to_rgb8`]).
    pub fn from_linear(image: &Image) -> Self {
        Self {
            width: image.width,
            height: image.height,
            data: image.to_rgb8(),
        }
    }

    /// The pixel at `(x, y)`.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// The number of pixels.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The image as linear values k/255 a channel, which the lab's display writes back as the
    /// same bytes (k/255 · 255 rounds to k for every k): so it is saved by the film's writer
    /// ([`Image::save`]: a temporary file renamed into place).
    pub fn to_image(&self) -> Image {
        Image {
            width: self.width,
            height: self.height,
            pixels: self
                .data
                .chunks_exact(3)
                .map(|p| glam::Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0)
                .collect(),
        }
    }
}

/// Whether two pixels are within [`TOLERANCE`] in every channel.
#[inline]
pub fn close(a: &[u8], b: &[u8]) -> bool {
    a.iter().zip(b).all(|(a, b)| a.abs_diff(*b) <= TOLERANCE)
}

/// Which pixels of `image` lie within [`TOLERANCE`] of one of `looks` in every channel (all of
/// the same size): one `bool` a pixel.
pub fn within_any(image: &Rgb8, looks: &[&Rgb8]) -> Vec<bool> {
    image
        .data
        .par_chunks_exact(3)
        .enumerate()
        .map(|(i, p)| looks.iter().any(|l| close(p, &l.data[3 * i..3 * i + 3])))
        .collect()
}

/// The share of pixels of `a` within [`TOLERANCE`] of `b` in every channel (1 for two empty
/// images).
pub fn share_within(a: &Rgb8, b: &Rgb8) -> f64 {
    share(&within_any(a, &[b]))
}

/// The share of `true` in `flags` (1 when empty).
pub fn share(flags: &[bool]) -> f64 {
    if flags.is_empty() {
        return 1.0;
    }
    flags.iter().filter(|f| **f).count() as f64 / flags.len() as f64
}

/// Whether `a` and `b` differ anywhere by more than [`TOLERANCE`]: an image that does not is
/// the same figure, as far as a comparison can tell.
pub fn differs(a: &Rgb8, b: &Rgb8) -> bool {
    a.data
        .par_chunks_exact(3)
        .zip(b.data.par_chunks_exact(3))
        .any(|(a, b)| !close(a, b))
}

/// The block where two images differ most.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WorstBlock {
    /// Its pixels: `x0 ≤ x < x1`, `y0 ≤ y < y1` (a block at the right or bottom edge may be
    /// narrower than [`BLOCK`]).
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
    /// The mean of |A − B| over its pixels and channels, in 255ths.
    pub mean_difference: f64,
}

/// The [`BLOCK`]-sided block (of the grid from the top-left corner) with the largest mean
/// |A − B|; the first in reading order among equals. `None` for empty images.
pub fn worst_block(a: &Rgb8, b: &Rgb8) -> Option<WorstBlock> {
    let (w, h) = (a.width, a.height);
    let (columns, rows) = (w.div_ceil(BLOCK), h.div_ceil(BLOCK));
    let blocks: Vec<WorstBlock> = (0..rows * columns)
        .into_par_iter()
        .map(|k| {
            let (x0, y0) = ((k % columns) * BLOCK, (k / columns) * BLOCK);
            let (x1, y1) = ((x0 + BLOCK).min(w), (y0 + BLOCK).min(h));
            let mut sum = 0u64;
            for y in y0..y1 {
                let start = 3 * (y as usize * w as usize + x0 as usize);
                let end = 3 * (y as usize * w as usize + x1 as usize);
                sum += a.data[start..end]
                    .iter()
                    .zip(&b.data[start..end])
                    .map(|(a, b)| u64::from(a.abs_diff(*b)))
                    .sum::<u64>();
            }
            let values = 3 * u64::from(x1 - x0) * u64::from(y1 - y0);
            WorstBlock {
                x0,
                y0,
                x1,
                y1,
                mean_difference: sum as f64 / values as f64,
            }
        })
        .collect();
    blocks.into_iter().reduce(|best, b| {
        if b.mean_difference > best.mean_difference {
            b
        } else {
            best
        }
    })
}

/// How much the difference picture of `a` and `b` amplifies |A − B|: [`DIFF_GAIN`], unless
/// more than half of the channels that differ would be white at that
/// gain (a factor, a missing term: differences everywhere of tens of levels); then the largest
/// difference is shown white (a gain of 255 / max, at least 1), so the difference's structure
/// stays visible.
pub fn difference_gain(a: &Rgb8, b: &Rgb8) -> f64 {
    let (differing, white, max) = a
        .data
        .par_iter()
        .zip(&b.data)
        .map(|(a, b)| {
            let d = u32::from(a.abs_diff(*b));
            (usize::from(d > 0), usize::from(d * DIFF_GAIN >= 255), d)
        })
        .reduce(|| (0, 0, 0), |x, y| (x.0 + y.0, x.1 + y.1, x.2.max(y.2)));
    if 2 * white > differing {
        (255.0 / f64::from(max)).max(1.0)
    } else {
        f64::from(DIFF_GAIN)
    }
}

/// |A − B| per channel, times [`difference_gain`] (and rounded), clamped at 255: black where
/// the images agree.
pub fn difference_picture(a: &Rgb8, b: &Rgb8) -> Rgb8 {
    difference_picture_with_gain(a, b, difference_gain(a, b))
}

/// |A − B| per channel, times `gain` (and rounded), clamped at 255.
pub fn difference_picture_with_gain(a: &Rgb8, b: &Rgb8, gain: f64) -> Rgb8 {
    Rgb8 {
        width: a.width,
        height: a.height,
        data: a
            .data
            .par_iter()
            .zip(&b.data)
            .map(|(a, b)| (f64::from(a.abs_diff(*b)) * gain).round().min(255.0) as u8)
            .collect(),
    }
}

/// The share of pixels of `image` that the figure `reference` explains once anti-aliasing is
/// allowed for: a pixel within [`TOLERANCE`] of the figure's, or, on an edge of the figure (a
/// pixel whose 3 × 3 neighbourhood is not one colour), within the range each channel takes in
/// that neighbourhood (± [`TOLERANCE`]). `margin` is the figure with a pixel more on every side
/// (its pixel (x + 1, y + 1) is the figure's (x, y)): the neighbourhoods of the image's border
/// pixels, which see past the image's edge.
///
/// Why this measures anti-aliasing: a pixel of several samples averages what is seen across its
/// area, which on an edge is a blend of the colours on either side, and those are the colours
/// the figure's neighbouring pixel centres see. Inside a surface (a uniform neighbourhood
/// within tolerance) nothing may change, so a mistake that changes the shading still fails
/// there. Sampling each pixel at its corner instead of its centre passes too: it is the same
/// blend, with one sample.
pub fn share_explained_with_edges(image: &Rgb8, reference: &Rgb8, margin: &Rgb8) -> f64 {
    let w = image.width as usize;
    let mw = margin.width as usize;
    debug_assert_eq!(
        (margin.width, margin.height),
        (image.width + 2, image.height + 2)
    );
    let explained: Vec<bool> = (0..image.pixels())
        .into_par_iter()
        .map(|k| {
            let (x, y) = (k % w, k / w);
            let i = 3 * k;
            let p = &image.data[i..i + 3];
            if close(p, &reference.data[i..i + 3]) {
                return true;
            }
            // The neighbourhood of (x, y) is margin's (x..=x + 2, y..=y + 2).
            let (mut lo, mut hi) = ([255u8; 3], [0u8; 3]);
            for ny in y..=y + 2 {
                for nx in x..=x + 2 {
                    let j = 3 * (ny * mw + nx);
                    for c in 0..3 {
                        lo[c] = lo[c].min(margin.data[j + c]);
                        hi[c] = hi[c].max(margin.data[j + c]);
                    }
                }
            }
            let edge = (0..3).any(|c| hi[c] - lo[c] > TOLERANCE);
            edge && (0..3).all(|c| {
                p[c] >= lo[c].saturating_sub(TOLERANCE) && p[c] <= hi[c].saturating_add(TOLERANCE)
            })
        })
        .collect();
    share(&explained)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `image` with a pixel more on every side, each a copy of its nearest: a margin for
    /// [`share_explained_with_edges`] where nothing is known past the edge.
    fn with_copied_margin(image: &Rgb8) -> Rgb8 {
        let (w, h) = (image.width, image.height);
        let data = (0..h + 2)
            .flat_map(|y| (0..w + 2).map(move |x| (x, y)))
            .flat_map(|(x, y)| image.get(x.clamp(1, w) - 1, y.clamp(1, h) - 1))
            .collect();
        Rgb8 {
            width: w + 2,
            height: h + 2,
            data,
        }
    }

    fn grey(width: u32, height: u32, value: u8) -> Rgb8 {
        Rgb8 {
            width,
            height,
            data: vec![value; (width * height * 3) as usize],
        }
    }

    fn set(image: &mut Rgb8, x: u32, y: u32, rgb: [u8; 3]) {
        let i = 3 * (y * image.width + x) as usize;
        image.data[i..i + 3].copy_from_slice(&rgb);
    }

    /// A 4 × 4 image where 3 pixels differ by 3/255 in one channel (beyond the tolerance of 2)
    /// and 2 by 2/255 (within it): 13 of 16 match, 0.8125.
    #[test]
    fn the_share_within_two_of_255_by_hand() {
        let a = grey(4, 4, 100);
        let mut b = a.clone();
        set(&mut b, 0, 0, [103, 100, 100]);
        set(&mut b, 3, 1, [100, 97, 100]);
        set(&mut b, 2, 3, [100, 100, 103]);
        set(&mut b, 1, 1, [102, 98, 102]);
        set(&mut b, 2, 2, [100, 100, 98]);
        assert_eq!(share_within(&a, &b), 13.0 / 16.0);
        assert_eq!(share_within(&a, &a), 1.0);
        assert!(differs(&a, &b));
        let mut within = a.clone();
        set(&mut within, 1, 2, [102, 98, 100]);
        assert!(!differs(&a, &within), "2/255 is the same figure");
    }

    /// Either of two looks explains a pixel: 3 pixels off the first look, 2 of them on the
    /// second, so 15 of 16.
    #[test]
    fn any_of_two_looks_explains_a_pixel() {
        let image = grey(4, 4, 50);
        let first = {
            let mut f = image.clone();
            set(&mut f, 0, 0, [0, 0, 0]);
            set(&mut f, 1, 0, [0, 0, 0]);
            set(&mut f, 2, 0, [0, 0, 0]);
            f
        };
        let mut second = grey(4, 4, 0);
        set(&mut second, 0, 0, [50, 51, 49]);
        set(&mut second, 1, 0, [52, 50, 50]);
        assert_eq!(share(&within_any(&image, &[&first, &second])), 15.0 / 16.0);
    }

    /// A 40 × 35 pair differing in one channel of one pixel, by 72, in the block from
    /// (32, 32): that block is 8 × 3 pixels, 72 values, so its mean |A − B| is 72 / 72 = 1.0;
    /// every other block's is 0.
    #[test]
    fn the_worst_block_by_hand() {
        let a = grey(40, 35, 10);
        let mut b = a.clone();
        set(&mut b, 35, 33, [82, 10, 10]);
        let worst = worst_block(&a, &b).unwrap();
        assert_eq!(
            worst,
            WorstBlock {
                x0: 32,
                y0: 32,
                x1: 40,
                y1: 35,
                mean_difference: 1.0
            }
        );
        // The same images: the first block, difference 0.
        let same = worst_block(&a, &a).unwrap();
        assert_eq!((same.x0, same.y0, same.x1, same.y1), (0, 0, 32, 32));
        assert_eq!(same.mean_difference, 0.0);
    }

    /// |A − B| × 8, clamped: 0 → 0, 2 → 16, 40 → 255.
    #[test]
    fn the_difference_picture_amplifies_by_eight() {
        let a = grey(2, 1, 100);
        let mut b = a.clone();
        set(&mut b, 0, 0, [102, 100, 60]);
        let d = difference_picture(&a, &b);
        assert_eq!(d.data, [16, 0, 255, 0, 0, 0]);
        // Saved through the film, k/255 comes back as k.
        let all = Rgb8 {
            width: 256,
            height: 1,
            data: (0..=255u8).flat_map(|k| [k, k, k]).collect(),
        };
        assert_eq!(Rgb8::from_linear(&all.to_image()), all);
    }

    /// An image that differs by tens of levels nearly everywhere (the figure × 0.6) is not
    /// white all over: its largest difference is shown white, the rest in proportion.
    #[test]
    fn a_difference_everywhere_is_scaled_to_its_largest() {
        let a = Rgb8 {
            width: 4,
            height: 1,
            data: vec![100, 100, 100, 200, 200, 200, 50, 50, 50, 0, 0, 0],
        };
        let b = Rgb8 {
            data: a
                .data
                .iter()
                .map(|v| (f64::from(*v) * 0.6).round() as u8)
                .collect(),
            ..a.clone()
        };
        assert_eq!(difference_gain(&a, &b), 255.0 / 80.0);
        let d = difference_picture(&a, &b);
        assert_eq!(d.data, [128, 128, 128, 255, 255, 255, 64, 64, 64, 0, 0, 0]);
    }

    /// A figure with a vertical edge between columns 1 and 2 (red | blue): a pixel of the
    /// edge columns at a red–blue blend is explained; a blend inside the blue (column 3, whose
    /// neighbourhood is all blue) is not, nor is a green no neighbour has.
    #[test]
    fn anti_aliased_edges_are_explained_and_flat_areas_are_not() {
        let (red, blue) = ([200, 0, 0], [0, 0, 200]);
        let mut figure = grey(4, 3, 0);
        for y in 0..3 {
            for x in 0..4 {
                set(&mut figure, x, y, if x < 2 { red } else { blue });
            }
        }
        let mut image = figure.clone();
        for y in 0..3 {
            set(&mut image, 1, y, [150, 0, 50]);
            set(&mut image, 2, y, [60, 0, 140]);
        }
        assert_eq!(share_within(&image, &figure), 6.0 / 12.0);
        assert_eq!(
            share_explained_with_edges(&image, &figure, &with_copied_margin(&figure)),
            1.0
        );
        set(&mut image, 3, 1, [60, 0, 140]);
        assert_eq!(
            share_explained_with_edges(&image, &figure, &with_copied_margin(&figure)),
            11.0 / 12.0
        );
        set(&mut image, 2, 0, [0, 200, 0]);
        assert_eq!(
            share_explained_with_edges(&image, &figure, &with_copied_margin(&figure)),
            10.0 / 12.0
        );
    }
}
