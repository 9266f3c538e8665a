//! The pinhole camera of lab sections 3 and 4: a position, a rotation `R` (yaw about y, plus an
//! optional pitch), a focal length in pixels and an image size.
//!
//! Axes follow the lab: x right, **y down**, z forward. With yaw and pitch 0 the camera looks
//! along +z; positive yaw turns the view to the right (forward moves toward +x); positive pitch
//! tilts it up (toward −y). The lab's camera has only yaw; pitch is 0 by default and the lab's
//! figures never use it.
//!
//! **A camera on a surface.** A camera may stand exactly on a surface: on a wall of the box, or
//! in one of its corners. It sees what lies in front of it, as if it stood a hair in front of
//! the surface: a ray does not hit what it starts on (hits need `t > 0`, see
//! [`crate::shapes::intersect`]), so the surface the camera stands on is not seen, and a ray leaving
//! through it goes on beyond it (out of the box: black). From the corner (−1, −1, −1) looking
//! along +z, the quarter of the rays that go into the box see it and the rest see nothing
//! (tests/faults.rs works it out by hand).

use glam::{Mat3, Vec3};
use serde::{Deserialize, Serialize};

use crate::base::geometry::Ray;
use crate::base::memory::{AllocError, try_with_capacity};

/// Radians from an angle in degrees as a person types it (the command line's `--yaw` and
/// `--pitch`, a scene file's angles): converted in `f64` and rounded to `f32` once, so that the
/// same typed number gives the same angle wherever it is typed, and every `f32` angle has a
/// decimal in degrees that gives it back ([`degrees`]).
pub fn radians(degrees: f64) -> f32 {
    degrees.to_radians() as f32
}

/// The shortest decimal in degrees that [`radians`] turns back into `radians` bit for bit: what
/// a scene file writes, so that saving and loading keeps every angle exactly (`10°` set on the
/// command line is written `10.0`, not `9.999999747378752`). A NaN has no such decimal and is
/// written as it converts.
pub fn degrees(radians: f32) -> f64 {
    let exact = f64::from(radians).to_degrees();
    // At most 17 significant digits name any f64; the conversion back to f32 then rounds to
    // `radians` itself, its error being ~1e−16 of the value against the f32's half step of 6e−8.
    (0..17)
        .filter_map(|digits| format!("{exact:.digits$e}").parse::<f64>().ok())
        .find(|&d| self::radians(d).to_bits() == radians.to_bits())
        .unwrap_or(exact)
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Camera {
    /// The pinhole: every primary ray starts here.
    pub position: Vec3,
    /// Rotation about the y axis, in radians (typed in degrees in the workbench, on the command
    /// line and in scene files: [`radians`], [`degrees`]).
    pub yaw: f32,
    /// Rotation about the camera's x axis, in radians; positive looks up.
    pub pitch: f32,
    /// Distance from the pinhole to the image plane, in pixels (the lab's `f`).
    pub focal_length: f32,
    /// Image width `W` in pixels.
    pub width: u32,
    /// Image height `H` in pixels.
    pub height: u32,
    /// Radius of the thin lens's aperture, in scene units; 0 is the lab's pinhole (everything
    /// sharp). Depth of field, one of the lab's extensions.
    pub aperture: f32,
    /// Distance from the lens to the plane in focus, along the view direction, in scene units.
    /// Only matters with an aperture above 0.
    pub focus_distance: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Self::default_for(512, 512)
    }
}

impl Camera {
    /// The lab's default camera for a `width × height` image: at (0, 0, −3.001), looking along
    /// +z, with `f = W` (a horizontal field of view of 2·atan(1/2) = 53.13°).
    pub fn default_for(width: u32, height: u32) -> Self {
        Self {
            position: Vec3::new(0.0, 0.0, -3.001),
            yaw: 0.0,
            pitch: 0.0,
            focal_length: width as f32,
            width,
            height,
            aperture: 0.0,
            focus_distance: Self::DEFAULT_FOCUS_DISTANCE,
        }
    }

    /// The focus distance by default: the default camera to the box's centre, 3.001.
    pub const DEFAULT_FOCUS_DISTANCE: f32 = 3.001;

    /// The rotation `R` whose columns are right, down and forward (lab section 4):
    /// `R = R_y(yaw) · R_x(pitch)`.
    pub fn rotation(&self) -> Mat3 {
        Mat3::from_rotation_y(self.yaw) * Mat3::from_rotation_x(self.pitch)
    }

    pub fn right(&self) -> Vec3 {
        self.rotation().x_axis
    }

    pub fn down(&self) -> Vec3 {
        self.rotation().y_axis
    }

    pub fn forward(&self) -> Vec3 {
        self.rotation().z_axis
    }

    /// The ray through the image-plane point `(px, py)`, in pixels from the top-left corner:
    /// direction `R · (px − W/2, py − H/2, f)` (lab equation 24, with its `y − W/2` typo read as
    /// `y − H/2`). The centre of pixel `(x, y)` is `(x + 0.5, y + 0.5)`.
    pub fn primary_ray(&self, px: f32, py: f32) -> Ray {
        self.primary_ray_rotated(&self.rotation(), px, py)
    }

    /// [`Camera::primary_ray`] with `R` = [`Camera::rotation`] computed once by the caller: a
    /// render pass makes it once, not once per pixel (its sines and cosines cost more than
    /// tracing a ray through the Cornell box).
    #[inline]
    pub fn primary_ray_rotated(&self, rotation: &Mat3, px: f32, py: f32) -> Ray {
        let d = Vec3::new(
            px - self.width as f32 / 2.0,
            py - self.height as f32 / 2.0,
            self.focal_length,
        );
        Ray::new(self.position, *rotation * d)
    }

    /// The ray of a thin lens through the image-plane point `(px, py)` and the lens point
    /// `lens` (on the unit disk, scaled by [`Camera::aperture`]).
    ///
    /// Every lens point's ray for `(px, py)` passes through the same point of the plane in focus,
    /// the point the pinhole ray reaches at depth [`Camera::focus_distance`] along the view
    /// direction: points on that plane are sharp. A point at depth z is seen through the lens
    /// point ℓ (camera coordinates, scene units) at image position `f·x/z + f·ℓ·(1/F − 1/z)`
    /// (F the focus distance, f the focal length in pixels), so its image spreads over a disk
    /// of radius `f · aperture · |1/F − 1/z|` pixels: the circle of confusion.
    #[inline]
    pub fn lens_ray_rotated(&self, rotation: &Mat3, px: f32, py: f32, lens: glam::Vec2) -> Ray {
        let d = Vec3::new(
            px - self.width as f32 / 2.0,
            py - self.height as f32 / 2.0,
            self.focal_length,
        );
        let focus = d * (self.focus_distance / self.focal_length);
        let on_lens = Vec3::new(self.aperture * lens.x, self.aperture * lens.y, 0.0);
        Ray::new(
            self.position + *rotation * on_lens,
            *rotation * (focus - on_lens),
        )
    }

    /// Where the point `p` appears in the image, in pixels from the top-left corner (the
    /// inverse of [`Camera::primary_ray`]: `(f·x/z + W/2, f·y/z + H/2)` for `p` at `(x, y, z)` in
    /// camera coordinates, `R⁻¹·(p − position)`), and its depth z; `None` when it is behind the
    /// camera or in its plane. The point may lie outside the image. The workbench draws the
    /// light where this says.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32, f32)> {
        let q = self.rotation().transpose() * (p - self.position);
        if !(q.z > 1e-6) || !q.is_finite() {
            return None;
        }
        let f = self.focal_length;
        Some((
            f * q.x / q.z + self.width as f32 / 2.0,
            f * q.y / q.z + self.height as f32 / 2.0,
            q.z,
        ))
    }

    /// The point at depth `depth` that appears at image position `(px, py)`: the inverse of
    /// [`Camera::project`]. Dragging the light's marker moves the light with it at its depth.
    pub fn unproject(&self, px: f32, py: f32, depth: f32) -> Vec3 {
        let f = self.focal_length;
        let q = Vec3::new(
            (px - self.width as f32 / 2.0) * depth / f,
            (py - self.height as f32 / 2.0) * depth / f,
            depth,
        );
        self.position + self.rotation() * q
    }

    /// The depth of a point along the view direction: its distance from the plane of the lens.
    pub fn depth_of(&self, point: Vec3) -> f32 {
        (point - self.position).dot(self.forward())
    }

    /// The ray through the centre of pixel `(x, y)`.
    pub fn pixel_ray(&self, x: u32, y: u32) -> Ray {
        self.primary_ray(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// Horizontal field of view, `2·atan(W/2 / f)`, in degrees.
    pub fn horizontal_fov_degrees(&self) -> f32 {
        2.0 * (self.width as f32 / 2.0 / self.focal_length)
            .atan()
            .to_degrees()
    }

    /// Vertical field of view, `2·atan(H/2 / f)`, in degrees.
    pub fn vertical_fov_degrees(&self) -> f32 {
        2.0 * (self.height as f32 / 2.0 / self.focal_length)
            .atan()
            .to_degrees()
    }

    /// Turns the camera (yaw and pitch) so that `target` is at the centre of the image. A target
    /// at the camera's own position leaves it unchanged.
    pub fn look_at(&mut self, target: Vec3) {
        let d = target - self.position;
        let horizontal = (d.x * d.x + d.z * d.z).sqrt();
        if d.length_squared() == 0.0 || !d.is_finite() {
            return;
        }
        self.yaw = d.x.atan2(d.z);
        self.pitch = (-d.y).atan2(horizontal);
    }

    /// The same view at another resolution: focal length scales with the width, so the field of
    /// view is kept. Used for the progressive preview and when the user changes the image size.
    pub fn with_resolution(&self, width: u32, height: u32) -> Self {
        Self {
            focal_length: self.focal_length * width as f32 / self.width as f32,
            width,
            height,
            ..*self
        }
    }

    /// Moves the camera along its own forward axis, projected on the floor plane, as the lab's
    /// Up/Down keys do (the y position stays put when pitched).
    pub fn move_forward(&mut self, distance: f32) {
        let f = Mat3::from_rotation_y(self.yaw).z_axis;
        self.position += distance * f;
    }
}

/// Where a batch of camera rays cross the image plane (and the lens): what a render pass hands
/// the tracer ([`crate::transport::integrator::Tracer::trace_camera`]) instead of the rays, so that the
/// rays are made inside the tracer's code compiled for the CPU ([`ImagePoints::rays`]). (A
/// closure making them would be compiled without the CPU's instruction set; made one at a
/// time, outside, they cost an eighth of a lab pass.)
#[derive(Clone, Copy, Debug)]
pub struct ImagePoints<'a> {
    pub camera: &'a Camera,
    /// [`Camera::rotation`], made once a pass.
    pub rotation: &'a Mat3,
    /// Each ray's image point, in pixels from the top-left corner.
    pub px: &'a [f32],
    pub py: &'a [f32],
    /// Each ray's lens point on the unit disk; ignored for a pinhole (and then may be empty).
    pub lens_x: &'a [f32],
    pub lens_y: &'a [f32],
}

impl ImagePoints<'_> {
    /// How many rays.
    pub fn len(&self) -> usize {
        self.px.len()
    }

    pub fn is_empty(&self) -> bool {
        self.px.is_empty()
    }

    /// Rays `first..first + out.len()` (at most [`ImagePoints::MAX_RAYS`]), into `out`:
    /// [`Camera::primary_ray_rotated`], or [`Camera::lens_ray_rotated`] with an aperture.
    ///
    /// Each is made by that very function, in a loop over arrays (image points in, origins and
    /// directions out) that LLVM vectorises: sixteen rays an AVX-512 instruction, the same IEEE
    /// operations in each lane, so the same rays bit for bit (tested). Written straight into
    /// `out`, whose rays interleave the six numbers, the loop was not vectorised.
    #[inline(always)]
    pub fn rays(&self, first: usize, out: &mut [Ray]) {
        let n = out.len();
        assert!(n <= Self::MAX_RAYS);
        let (px, py) = (&self.px[first..][..n], &self.py[first..][..n]);
        let mut origin = [[0.0; Self::MAX_RAYS]; 3];
        let mut direction = [[0.0; Self::MAX_RAYS]; 3];
        let mut put = |k: usize, ray: Ray| {
            [origin[0][k], origin[1][k], origin[2][k]] = ray.origin.to_array();
            [direction[0][k], direction[1][k], direction[2][k]] = ray.direction.to_array();
        };
        if self.camera.aperture > 0.0 {
            let (lx, ly) = (&self.lens_x[first..][..n], &self.lens_y[first..][..n]);
            for k in 0..n {
                let lens = glam::Vec2::new(lx[k], ly[k]);
                put(
                    k,
                    self.camera
                        .lens_ray_rotated(self.rotation, px[k], py[k], lens),
                );
            }
        } else {
            for k in 0..n {
                put(
                    k,
                    self.camera.primary_ray_rotated(self.rotation, px[k], py[k]),
                );
            }
        }
        for (k, ray) in out.iter_mut().enumerate() {
            *ray = Ray {
                origin: Vec3::new(origin[0][k], origin[1][k], origin[2][k]),
                direction: Vec3::new(direction[0][k], direction[1][k], direction[2][k]),
            };
        }
    }

    /// The most rays [`ImagePoints::rays`] makes at a time.
    pub const MAX_RAYS: usize = 64;
}

/// The camera's rays through every pixel centre, row by row.
pub fn primary_rays(camera: &Camera) -> Vec<Ray> {
    (0..camera.height)
        .flat_map(|y| (0..camera.width).map(move |x| camera.pixel_ray(x, y)))
        .collect()
}

/// [`primary_rays`], reserved fallibly: too many for the memory is an error, not an abort.
pub fn try_primary_rays(camera: &Camera) -> Result<Vec<Ray>, AllocError> {
    let len = camera.width as usize * camera.height as usize;
    let mut rays = try_with_capacity(len, || {
        format!("the {}×{} camera rays", camera.width, camera.height)
    })?;
    rays.extend(
        (0..camera.height).flat_map(|y| (0..camera.width).map(move |x| camera.pixel_ray(x, y))),
    );
    Ok(rays)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::accel::Isa;
    use crate::shapes::accel::set::{Compiled, InstructionSet};

    /// [`ImagePoints::rays`] as the tracer calls it, compiled for an instruction set as
    /// `Tracer::trace_camera` is.
    struct Rays<'a, 'b> {
        points: &'a ImagePoints<'b>,
        out: &'a mut [Ray],
    }

    impl Compiled for Rays<'_, '_> {
        type Output = ();

        #[inline(always)]
        fn run<S: InstructionSet>(self, _: S) {
            self.points.rays(0, self.out);
        }
    }

    /// The camera rays made a batch at a time ([`ImagePoints::rays`], compiled for each
    /// instruction set the CPU has) are the rays [`Camera::primary_ray_rotated`] and
    /// [`Camera::lens_ray_rotated`] make one at a time, bit for bit: pixel centres, jittered
    /// points, points far outside the image and the image's centre (a zero direction for a
    /// zero focal length), batches of every length up to 64.
    #[test]
    fn camera_rays_a_batch_at_a_time_equal_one_at_a_time() {
        let builds = Isa::available_for_tests("camera_rays_a_batch_at_a_time_equal_one_at_a_time");
        let mut rng = crate::base::sampling::Rng::for_pixel_sample(3, 1, 4, 1);
        let mut turned = Camera::default_for(61, 47);
        turned.yaw = 0.7;
        turned.pitch = -0.3;
        let mut lens = turned;
        lens.aperture = 0.2;
        lens.focus_distance = 2.5;
        let mut flat = Camera::default_for(8, 8);
        flat.focal_length = 0.0;
        for camera in [Camera::default(), turned, lens, flat] {
            let rotation = camera.rotation();
            let (w, h) = (camera.width as f32, camera.height as f32);
            for n in [1, 15, 16, 17, 61, 64] {
                let mut px = Vec::new();
                let mut py = Vec::new();
                let (mut lx, mut ly) = (Vec::new(), Vec::new());
                for k in 0..n {
                    let (x, y) = match k % 4 {
                        0 => ((k % 7) as f32 + 0.5, (k % 5) as f32 + 0.5),
                        1 => (rng.next_f32() * w, rng.next_f32() * h),
                        2 => (w / 2.0, h / 2.0),
                        _ => (1e6 * (rng.next_f32() - 0.5), -3e5 * rng.next_f32()),
                    };
                    px.push(x);
                    py.push(y);
                    lx.push(rng.next_f32() * 2.0 - 1.0);
                    ly.push(rng.next_f32() * 2.0 - 1.0);
                }
                let points = ImagePoints {
                    camera: &camera,
                    rotation: &rotation,
                    px: &px,
                    py: &py,
                    lens_x: &lx,
                    lens_y: &ly,
                };
                let bits = |r: &Ray| {
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    (bits(r.origin), bits(r.direction))
                };
                for &isa in &builds {
                    let build = isa.name();
                    let mut out = vec![Ray::new(Vec3::ZERO, Vec3::Z); n];
                    isa.call(Rays {
                        points: &points,
                        out: &mut out,
                    });
                    for (k, got) in out.iter().enumerate() {
                        let one = if camera.aperture > 0.0 {
                            let lens = glam::Vec2::new(lx[k], ly[k]);
                            camera.lens_ray_rotated(&rotation, px[k], py[k], lens)
                        } else {
                            camera.primary_ray_rotated(&rotation, px[k], py[k])
                        };
                        assert_eq!(bits(got), bits(&one), "{build} {camera:?} {k} of {n}");
                    }
                }
            }
        }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn centre_ray_points_along_forward() {
        // For an even W the image centre is the corner shared by four pixels: (W/2, H/2).
        let cam = Camera::default_for(512, 384);
        let r = cam.primary_ray(256.0, 192.0);
        assert_eq!(r.origin, Vec3::new(0.0, 0.0, -3.001));
        assert!(close(r.direction, Vec3::Z));
        let mut turned = cam;
        turned.yaw = 0.3;
        assert!(close(
            turned.primary_ray(256.0, 192.0).direction,
            turned.forward()
        ));
    }

    #[test]
    fn corner_rays_match_the_field_of_view() {
        // W = H = 512, f = 512: the image's left edge is at atan(256/512) = 26.565° from forward,
        // so the horizontal field of view is 53.130°.
        let cam = Camera::default_for(512, 512);
        assert!((cam.horizontal_fov_degrees() - 53.130_1).abs() < 1e-3);
        assert!((cam.vertical_fov_degrees() - 53.130_1).abs() < 1e-3);
        let left = cam.primary_ray(0.0, 256.0).direction;
        let half = left.x.abs().atan2(left.z).to_degrees();
        assert!((2.0 * half - cam.horizontal_fov_degrees()).abs() < 1e-3);
        // A 512×256 image with f = 512: vertical field of view 2·atan(128/512) = 28.072°.
        let wide = Camera::default_for(512, 256);
        assert!((wide.vertical_fov_degrees() - 28.072_5).abs() < 1e-3);
        let top = wide.primary_ray(256.0, 0.0).direction;
        assert!((2.0 * top.y.abs().atan2(top.z).to_degrees() - 28.072_5).abs() < 1e-3);
        // The top-left corner ray goes left (−x) and up (−y).
        let corner = cam.primary_ray(0.0, 0.0).direction;
        assert!(corner.x < 0.0 && corner.y < 0.0 && corner.z > 0.0);
    }

    #[test]
    fn yaw_90_turns_forward_to_plus_x() {
        let mut cam = Camera::default();
        cam.yaw = 90f32.to_radians();
        assert!(close(cam.forward(), Vec3::X));
        // Right turns from +x to −z, down stays +y.
        assert!(close(cam.right(), Vec3::new(0.0, 0.0, -1.0)));
        assert!(close(cam.down(), Vec3::Y));
    }

    #[test]
    fn look_at_faces_its_target() {
        let mut cam = Camera::default();
        for target in [
            Vec3::ZERO,
            Vec3::new(0.7, 0.0, 0.5),
            Vec3::new(-0.5, 0.9, 1.0),
            Vec3::new(0.2, -0.8, -5.0),
        ] {
            cam.look_at(target);
            let to_target = (target - cam.position).normalize();
            assert!(close(cam.forward(), to_target), "{target}");
            let centre = cam.primary_ray(256.0, 256.0);
            assert!(close(centre.direction, to_target));
        }
        // The box centre is straight ahead of the default camera: yaw and pitch stay 0.
        let mut cam = Camera::default();
        cam.look_at(Vec3::ZERO);
        assert_eq!((cam.yaw, cam.pitch), (0.0, 0.0));
    }

    #[test]
    fn with_resolution_keeps_the_field_of_view() {
        let cam = Camera::default_for(1024, 768);
        let small = cam.with_resolution(128, 96);
        assert_eq!(small.focal_length, 128.0);
        assert!((small.horizontal_fov_degrees() - cam.horizontal_fov_degrees()).abs() < 1e-4);
    }

    /// A point at the focus distance is sharp: the rays of every lens point through a pixel
    /// meet at one point of the focus plane, and so its image does not spread.
    #[test]
    fn the_focus_plane_is_sharp() {
        let mut cam = Camera::default_for(256, 256);
        cam.yaw = 0.2;
        cam.aperture = 0.1;
        cam.focus_distance = 2.5;
        let r = cam.rotation();
        let (px, py) = (60.3, 190.7);
        let pinhole = cam.primary_ray_rotated(&r, px, py);
        // Where the pinhole ray reaches depth 2.5.
        let target = pinhole.at(2.5 / pinhole.direction.dot(cam.forward()));
        for lens in [
            glam::Vec2::new(1.0, 0.0),
            glam::Vec2::new(-0.6, 0.8),
            glam::Vec2::new(0.0, -1.0),
            glam::Vec2::new(0.3, 0.2),
        ] {
            let ray = cam.lens_ray_rotated(&r, px, py, lens);
            let t = (target - ray.origin).dot(ray.direction);
            let miss = (ray.at(t) - target).length();
            // Well under a pixel at that depth (a pixel is 2.5/256 ≈ 0.01 wide there).
            assert!(miss < 1e-5, "{lens}: {miss}");
        }
        // Aperture 0 is the pinhole ray.
        cam.aperture = 0.0;
        let r0 = cam.lens_ray_rotated(&r, px, py, glam::Vec2::new(1.0, 0.0));
        assert!((r0.direction - pinhole.direction).length() < 1e-6);
        assert_eq!(r0.origin, pinhole.origin);
    }

    /// A point away from the focus plane spreads over the circle of confusion. Derivation (lens
    /// in the plane z = 0 of camera space, focal length f in pixels, focus distance F, lens
    /// point ℓ): the ray from ℓ through pixel position p (camera-space image point
    /// (p, f)) passes through p·F/f on the focus plane, so at depth z it is at
    /// ℓ + (p·F/f − ℓ)·z/F. It meets the point X (at depth z) when
    /// p = f·X/z + f·ℓ·(1/F − 1/z): the image of X moves by f·ℓ·(1/F − 1/z) as ℓ goes around
    /// the lens, a disk of radius f·A·|1/F − 1/z| pixels. Here f = 256, A = 0.05, F = 2,
    /// z = 4: 256 · 0.05 · (0.5 − 0.25) = 3.2 pixels.
    #[test]
    fn a_far_point_spreads_over_the_circle_of_confusion() {
        let mut cam = Camera::default_for(256, 256);
        cam.position = Vec3::ZERO;
        cam.aperture = 0.05;
        cam.focus_distance = 2.0;
        let r = cam.rotation();
        let point = Vec3::new(0.3, -0.2, 4.0);
        // The pixel position where the pinhole sees it.
        let (px, py) = (128.0 + 256.0 * 0.3 / 4.0, 128.0 - 256.0 * 0.2 / 4.0);
        // Each lens point's ray through that pixel misses the point at its depth by
        // ℓ·(z/F − 1) = 0.05 scene units; at depth 4 a pixel is 4/256 wide, so by 3.2 pixels:
        // the circle of confusion's radius, whichever way round the lens.
        let mut largest = 0.0f32;
        for k in 0..64 {
            let angle = k as f32 / 64.0 * std::f32::consts::TAU;
            let lens = glam::Vec2::new(angle.cos(), angle.sin());
            let ray = cam.lens_ray_rotated(&r, px, py, lens);
            let t = (4.0 - ray.origin.z) / ray.direction.z;
            let miss_in_pixels = (ray.at(t) - point).length() * (256.0 / 4.0);
            assert!(
                (miss_in_pixels - 3.2).abs() < 1e-3,
                "{lens}: {miss_in_pixels}"
            );
            largest = largest.max(miss_in_pixels);
        }
        assert!((largest - 3.2).abs() < 1e-3, "{largest}");
    }

    /// The lab's light (0, −0.5, −0.7) seen by the default 512² camera at (0, 0, −3.001): depth
    /// z = 2.301, so it appears at (256 + 512·0/2.301, 256 + 512·(−0.5)/2.301) =
    /// (256, 256 − 256/2.301) = (256, 144.744). Unprojecting that point at that depth gives the light back; a point
    /// behind the camera has no image.
    #[test]
    fn project_and_unproject_are_inverse() {
        let cam = Camera::default();
        let light = Vec3::new(0.0, -0.5, -0.7);
        let (px, py, z) = cam.project(light).unwrap();
        assert!(
            (px - 256.0).abs() < 1e-4 && (py - 144.744).abs() < 1e-3,
            "{px} {py}"
        );
        assert!((z - 2.301).abs() < 1e-5);
        assert!((cam.unproject(px, py, z) - light).length() < 1e-5);
        assert_eq!(cam.project(Vec3::new(0.0, 0.0, -4.0)), None);
        // Turned and pitched, a pixel's own ray passes through what it projects to.
        let mut turned = cam;
        turned.yaw = 0.4;
        turned.pitch = -0.2;
        let p = Vec3::new(0.3, 0.2, 0.5);
        let (px, py, z) = turned.project(p).unwrap();
        let ray = turned.primary_ray(px, py);
        let t = (p - ray.origin).length();
        assert!((ray.at(t) - p).length() < 1e-4);
        assert!((turned.unproject(px, py, z) - p).length() < 1e-4);
    }
}
