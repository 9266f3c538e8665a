//! Comparing an image that was stored lossily (JPEG) with a figure.
//!
//! JPEG codes each 8 × 8 block of an image by its cosine transform, quantised: the fine detail
//! goes first, so edges blur and ring by tens of levels and chroma smears across a colour
//! edge, while each block's mean (its DC coefficient, the most finely quantised) stays close.
//! So a JPEG is compared with a figure block by block: a pixel is explained where its block's
//! mean colour is within [`JPEG_TOLERANCE`] of the figure's over the same block, in every
//! channel. The exact figure (the lab's box at 96² and 256², every stage) saved by `image`'s
//! encoder at qualities 75 to 95 keeps its block means within 1.7/255 at the 99th percentile
//! at quality 90 and within 3.9/255 at the worst at quality 75; the classic mistakes change
//! the blocks they touch by tens of levels.

use rayon::prelude::*;
use serde::Serialize;

use super::compare::Rgb8;

/// How a student's image was stored, which decides how it is compared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    /// PNG, BMP, PPM: the pixels as written, compared pixel by pixel within 2/255.
    #[default]
    Lossless,
    /// JPEG: compared by its 8 × 8 blocks' means ([`within_any_blocks`]).
    Jpeg,
}

/// The side of JPEG's blocks, in pixels, from the image's top-left corner.
pub const JPEG_BLOCK: u32 = 8;

/// How far a block's mean may be from the figure's, in 255ths, each channel.
pub const JPEG_TOLERANCE: f64 = 3.0;

/// The note a check of a JPEG gets.
pub const JPEG_NOTE: &str = "the image is a JPEG: its compression moves pixels by a few levels \
     and blurs edges, so it is compared by the mean colour of its 8×8 blocks (within 3/255), \
     which JPEG keeps, not pixel by pixel; save PNG, BMP or PPM for an exact check";

/// Each block's mean colour, in reading order of the blocks.
fn block_means(image: &Rgb8) -> Vec<[f64; 3]> {
    let (w, h) = (image.width, image.height);
    let columns = w.div_ceil(JPEG_BLOCK);
    let rows = h.div_ceil(JPEG_BLOCK);
    (0..rows * columns)
        .into_par_iter()
        .map(|k| {
            let (x0, y0) = ((k % columns) * JPEG_BLOCK, (k / columns) * JPEG_BLOCK);
            let (x1, y1) = ((x0 + JPEG_BLOCK).min(w), (y0 + JPEG_BLOCK).min(h));
            let mut sum = [0u64; 3];
            for y in y0..y1 {
                for x in x0..x1 {
                    let p = image.get(x, y);
                    for c in 0..3 {
                        sum[c] += u64::from(p[c]);
                    }
                }
            }
            let n = f64::from((x1 - x0) * (y1 - y0));
            sum.map(|s| s as f64 / n)
        })
        .collect()
}

/// Which pixels of `image` (a JPEG) lie in a block whose mean colour is within
/// [`JPEG_TOLERANCE`] of one of `looks`' over the same block, in every channel: one `bool` a
/// pixel.
pub fn within_any_blocks(image: &Rgb8, looks: &[&Rgb8]) -> Vec<bool> {
    let mine = block_means(image);
    let theirs: Vec<Vec<[f64; 3]>> = looks.iter().map(|l| block_means(l)).collect();
    let explained: Vec<bool> = (0..mine.len())
        .map(|b| {
            theirs
                .iter()
                .any(|t| (0..3).all(|c| (mine[b][c] - t[b][c]).abs() <= JPEG_TOLERANCE))
        })
        .collect();
    let (w, columns) = (image.width, image.width.div_ceil(JPEG_BLOCK));
    (0..image.pixels())
        .map(|i| {
            let (x, y) = (i as u32 % w, i as u32 / w);
            explained[((y / JPEG_BLOCK) * columns + x / JPEG_BLOCK) as usize]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16 × 8 image of two blocks: the first's mean moved by 2.5 (explained), the second's
    /// by 3.5 in one channel (not), though every pixel of the first moved by more than 2.
    #[test]
    fn blocks_are_explained_by_their_means() {
        let figure = Rgb8 {
            width: 16,
            height: 8,
            data: vec![100; 16 * 8 * 3],
        };
        let mut image = figure.clone();
        for y in 0..8 {
            for x in 0..16 {
                let i = 3 * (y * 16 + x);
                if x < 8 {
                    // ±5 in a checkerboard, then 2.5 more on average.
                    let v: i32 = if (x + y) % 2 == 0 { 110 } else { 95 };
                    image.data[i] = v as u8;
                } else {
                    image.data[i + 1] = if x < 12 { 107 } else { 100 };
                }
            }
        }
        let flags = within_any_blocks(&image, &[&figure]);
        assert_eq!(flags.iter().filter(|f| **f).count(), 64);
        assert!(flags[0] && !flags[8]);
    }
}
