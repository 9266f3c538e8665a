//! How visible a difference is: the structural similarity (SSIM, Wang, Bovik, Sheikh and
//! Simoncelli 2004) of two 8-bit images' luminance.
//!
//! The 2/255 criterion ([`super::compare`]) decides whether an image is right; SSIM only ranks
//! how much a difference shows to the eye (a shift of one level everywhere scores near 1, a
//! wall of the wrong colour far lower). For each [`WINDOW`]² window, every [`STRIDE`] pixels:
//!
//! SSIM = (2·μx·μy + C1)(2·σxy + C2) / ((μx² + μy² + C1)(σx² + σy² + C2))
//!
//! with the window's means μ, its variances σ² and covariance σxy (each a mean over the
//! window's pixels, uniform weights), C1 = (0.01·255)², C2 = (0.03·255)²; the image's SSIM is
//! the mean over its windows. Luminance is Rec. 709's 0.2126 R + 0.7152 G + 0.0722 B of the
//! stored values. An image smaller than a window is one window.

use rayon::prelude::*;

use super::compare::Rgb8;

/// The side of the square windows, in pixels.
pub const WINDOW: usize = 8;

/// The step between windows, in pixels: windows overlap by half.
pub const STRIDE: usize = 4;

const C1: f64 = (0.01 * 255.0) * (0.01 * 255.0);
const C2: f64 = (0.03 * 255.0) * (0.03 * 255.0);

/// The luminance of each pixel, 0 to 255.
fn luminance(image: &Rgb8) -> Vec<f64> {
    image
        .data
        .chunks_exact(3)
        .map(|p| 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]))
        .collect()
}

/// The window origins along a side of `n` pixels: every [`STRIDE`] while a whole window
/// fits, and the last window flush with the edge.
fn origins(n: usize) -> Vec<usize> {
    if n <= WINDOW {
        return vec![0];
    }
    let mut o: Vec<usize> = (0..=n - WINDOW).step_by(STRIDE).collect();
    if o.last() != Some(&(n - WINDOW)) {
        o.push(n - WINDOW);
    }
    o
}

/// The SSIM of one window from its sums over `n` pixels: Σx, Σy, Σx², Σy², Σxy.
fn window_ssim(n: f64, [sx, sy, sxx, syy, sxy]: [f64; 5]) -> f64 {
    let (mx, my) = (sx / n, sy / n);
    // Not clamped at 0: for two identical windows these are the same bits, so their SSIM is
    // exactly 1.
    let vx = sxx / n - mx * mx;
    let vy = syy / n - my * my;
    let cov = sxy / n - mx * my;
    ((2.0 * mx * my + C1) * (2.0 * cov + C2)) / ((mx * mx + my * my + C1) * (vx + vy + C2))
}

/// The mean SSIM of `a` and `b` (the same size): 1 for identical images, lower the more
/// visible their difference.
pub fn ssim(a: &Rgb8, b: &Rgb8) -> f64 {
    debug_assert_eq!((a.width, a.height), (b.width, b.height));
    let (w, h) = (a.width as usize, a.height as usize);
    if w == 0 || h == 0 {
        return 1.0;
    }
    let (la, lb) = (luminance(a), luminance(b));
    let (xs, ys) = (origins(w), origins(h));
    let (ww, wh) = (WINDOW.min(w), WINDOW.min(h));
    let n = (ww * wh) as f64;
    let total: f64 = ys
        .par_iter()
        .map(|&y0| {
            xs.iter()
                .map(|&x0| {
                    let mut s = [0.0f64; 5];
                    for y in y0..y0 + wh {
                        for x in x0..x0 + ww {
                            let (x, y) = (la[y * w + x], lb[y * w + x]);
                            s[0] += x;
                            s[1] += y;
                            s[2] += x * x;
                            s[3] += y * y;
                            s[4] += x * y;
                        }
                    }
                    window_ssim(n, s)
                })
                .sum::<f64>()
        })
        .sum();
    total / (xs.len() * ys.len()) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grey image whose pixel (x, y) is `value(x, y)`.
    fn grey(width: u32, height: u32, value: impl Fn(u32, u32) -> u8) -> Rgb8 {
        let mut data = Vec::new();
        for y in 0..height {
            for x in 0..width {
                data.extend([value(x, y); 3]);
            }
        }
        Rgb8 {
            width,
            height,
            data,
        }
    }

    /// Two flat 8 × 8 greys, 100 and 110 (one window, no variance): SSIM is the luminance
    /// term alone, (2·100·110 + C1) / (100² + 110² + C1) with C1 = 2.55² = 6.5025:
    /// 22006.5025 / 22106.5025.
    #[test]
    fn flat_greys_by_hand() {
        let got = ssim(&grey(8, 8, |_, _| 100), &grey(8, 8, |_, _| 110));
        let want = 22006.5025 / 22106.5025;
        assert!((got - want).abs() < 1e-9, "{got} against {want}");
    }

    /// A checkerboard of 0 and 200 against flat 100, one window: the means are equal (100),
    /// σx² = 100² = 10000, σy² = 0, σxy = 0, so SSIM = C2 / (10000 + C2) with
    /// C2 = 7.65² = 58.5225: 0.005818…; against itself, 1.
    #[test]
    fn structure_lost_by_hand() {
        let checker = grey(8, 8, |x, y| if (x + y) % 2 == 0 { 0 } else { 200 });
        let got = ssim(&checker, &grey(8, 8, |_, _| 100));
        let want = 58.5225 / (10000.0 + 58.5225);
        assert!((got - want).abs() < 1e-9, "{got} against {want}");
        assert_eq!(ssim(&checker, &checker), 1.0);
        // A flat window, whose variance rounds to a little below 0: still exactly 1.
        let flat = grey(8, 8, |_, _| 77);
        assert_eq!(ssim(&flat, &flat), 1.0);
    }

    /// The windows of a 12-pixel side: at 0 and 4 (a stride of 4, the last flush with the
    /// edge); a 13-pixel side adds one flush at 5; a side of 8 or less is one window.
    #[test]
    fn windows_cover_the_image() {
        assert_eq!(origins(12), [0, 4]);
        assert_eq!(origins(13), [0, 4, 5]);
        assert_eq!(origins(8), [0]);
        assert_eq!(origins(3), [0]);
        // 12 × 8: two windows, the left one flat 100 against 110, the right one identical
        // (columns 8–11 are 50 in both, and columns 4–7 are shared: window 2 sees 100 | 50
        // against 110 | 50).
        let a = grey(12, 8, |x, _| if x < 8 { 100 } else { 50 });
        let b = grey(12, 8, |x, _| if x < 8 { 110 } else { 50 });
        let first = 22006.5025 / 22106.5025;
        // Window at x = 4: half 100 (or 110) and half 50. μa = 75, μb = 80, σa² = 625,
        // σb² = 900, σab = 750.
        let second = ((2.0 * 75.0 * 80.0 + C1) * (2.0 * 750.0 + C2))
            / ((75.0f64.powi(2) + 80.0f64.powi(2) + C1) * (625.0 + 900.0 + C2));
        let got = ssim(&a, &b);
        assert!((got - (first + second) / 2.0).abs() < 1e-9, "{got}");
    }
}
