//! `--explain`: what the genetic algorithm learned, drawn over the rendered image.
//!
//! The render is tone-mapped (its 99th luminance percentile to 0.6) and enlarged to at least
//! 768 pixels across so that the overlay stands out, then for every GA pixel:
//! * a small cross: white where the GA improved on `srt`, grey where `srt` was kept;
//! * for every evolved generator holding at least [`MIN_SHARE`] of the evolved weight, each
//!   anchor sampler's anchor point as a dot, coloured by the step it belongs to (first step
//!   yellow, then cyan, magenta, orange, …), and for the first step also a faint line from
//!   the pixel to the anchor and the cone's footprint around the anchor as seen from the
//!   pixel's first hit (radius `distance · tan θc`); each patch sampler's outline, in its
//!   step's colour.
//!
//! Opacity follows the generator's weight. The result is linear RGB like any other output.

use super::plan::Plan;
use crate::image::Image;
use crate::path::generator::DirectionSampler;
use crate::path::{RayCounts, SceneView};

/// Generators lighter than this share of a pixel's evolved weight are not drawn.
pub const MIN_SHARE: f64 = 0.2;
/// The explanation is enlarged to at least this width.
const MIN_WIDTH: u32 = 768;

/// Colours of the anchor steps, in order.
const STEP_COLOURS: [[f32; 3]; 5] = [
    [1.0, 0.85, 0.0],
    [0.0, 0.9, 1.0],
    [1.0, 0.2, 1.0],
    [1.0, 0.5, 0.0],
    [0.5, 1.0, 0.3],
];

struct Canvas {
    image: Image,
}

impl Canvas {
    fn blend(&mut self, x: i64, y: i64, colour: [f32; 3], alpha: f32) {
        if x < 0 || y < 0 || x >= self.image.width as i64 || y >= self.image.height as i64 {
            return;
        }
        let (x, y) = (x as u32, y as u32);
        let old = self.image.get(x, y);
        let new = std::array::from_fn(|c| old[c] * (1.0 - alpha) + colour[c] * alpha);
        self.image.set(x, y, new);
    }

    /// A segment, clipped to the image (Liang–Barsky) so that far-away ends cost nothing.
    fn line(&mut self, a: (f32, f32), b: (f32, f32), colour: [f32; 3], alpha: f32) {
        let (w, h) = (self.image.width as f32, self.image.height as f32);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for (p, q) in [(-dx, a.0), (dx, w - a.0), (-dy, a.1), (dy, h - a.1)] {
            if p == 0.0 {
                if q < 0.0 {
                    return;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if t0.is_nan() || t1.is_nan() || t0 > t1 {
            return;
        }
        let (x0, y0) = (a.0 + t0 * dx, a.1 + t0 * dy);
        let steps = ((t1 - t0) * dx.abs().max(dy.abs())).ceil().max(1.0) as usize;
        for i in 0..=steps {
            let t = i as f32 / steps as f32 * (t1 - t0);
            self.blend(
                (x0 + t * dx).floor() as i64,
                (y0 + t * dy).floor() as i64,
                colour,
                alpha,
            );
        }
    }

    fn dot(&mut self, c: (f32, f32), radius: i64, colour: [f32; 3], alpha: f32) {
        let (cx, cy) = (c.0.floor() as i64, c.1.floor() as i64);
        for y in -radius..=radius {
            for x in -radius..=radius {
                if x * x + y * y <= radius * radius {
                    self.blend(cx + x, cy + y, colour, alpha);
                }
            }
        }
    }

    fn circle(&mut self, c: (f32, f32), radius: f32, colour: [f32; 3], alpha: f32) {
        let n = (radius.min(4096.0) * 0.8).clamp(16.0, 512.0) as usize;
        let at = |i: usize| {
            let phi = i as f32 / n as f32 * std::f32::consts::TAU;
            (c.0 + radius * phi.cos(), c.1 + radius * phi.sin())
        };
        for i in 0..n {
            self.line(at(i), at(i + 1), colour, alpha);
        }
    }
}

/// The render tone-mapped to `[0, 0.6]` by its 99th luminance percentile, enlarged `scale`
/// times.
fn backdrop(image: &Image, scale: u32) -> Image {
    let lum = |p: [f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let mut values: Vec<f32> = (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .map(|(x, y)| lum(image.get(x, y)))
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let exposure = if values.is_empty() {
        1.0
    } else {
        let k = (values.len() - 1) * 99 / 100;
        let (_, p99, _) = values.select_nth_unstable_by(k, f32::total_cmp);
        0.6 / *p99
    };
    let tone = |c: f32| {
        if c.is_finite() {
            (c * exposure).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let mut out = Image::new(image.width * scale, image.height * scale);
    for y in 0..out.height {
        for x in 0..out.width {
            out.set(x, y, image.get(x / scale, y / scale).map(tone));
        }
    }
    out
}

/// The explanation image of `plan` over `render` (the size of the plan, enlarged).
pub fn draw(view: &SceneView, render: &Image, plan: &Plan) -> Image {
    let camera = &view.scene.camera;
    let scale = MIN_WIDTH.div_ceil(render.width.max(1)).max(1);
    let s = scale as f32;
    let mut canvas = Canvas {
        image: backdrop(render, scale),
    };
    for p in &plan.pixels {
        let ray = camera.ray(p.x as f32 + 0.5, p.y as f32 + 0.5);
        // The cones' apex: the pixel centre's first hit, traced once per GA pixel.
        let from = view
            .trace(&ray, &mut RayCounts::default())
            .map_or(ray.origin, |x1| x1.p);
        let centre = ((p.x as f32 + 0.5) * s, (p.y as f32 + 0.5) * s);
        let evolved: f64 = p.mixture.weights[1..].iter().sum();
        for (g, &w) in p.mixture.generators.iter().zip(&p.mixture.weights).skip(1) {
            if w < MIN_SHARE * evolved {
                continue;
            }
            let alpha = (0.3 + 0.7 * w / evolved) as f32;
            for (k, step) in g.steps.iter().enumerate() {
                let colour = STEP_COLOURS[k % STEP_COLOURS.len()];
                let a = match &step.sampler {
                    DirectionSampler::Anchor(a) => a,
                    DirectionSampler::Patch(p) => {
                        // The parallelogram's outline, where all four corners project.
                        let corners =
                            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(su, sv)| {
                                camera.project((p.center + su * p.half_u + sv * p.half_v).as_vec3())
                            });
                        if let [Some(a), Some(b), Some(c), Some(d)] = corners {
                            let corners = [a, b, c, d].map(|(x, y, _)| (x * s, y * s));
                            for i in 0..4 {
                                canvas.line(corners[i], corners[(i + 1) % 4], colour, 0.5 * alpha);
                            }
                        }
                        continue;
                    }
                    DirectionSampler::Brdf => continue,
                };
                let anchor = a.anchor.as_vec3();
                let Some((ax, ay, depth)) = camera.project(anchor) else {
                    continue;
                };
                let (ax, ay) = (ax * s, ay * s);
                canvas.dot((ax, ay), 2, colour, alpha);
                if k == 0 {
                    canvas.line(centre, (ax, ay), colour, 0.3 * alpha);
                    let radius = (anchor - from).length() * (a.theta_c.min(1.5) as f32).tan();
                    let radius = radius * camera.pixels_per_unit(depth) * s;
                    canvas.circle((ax, ay), radius, colour, 0.5 * alpha);
                }
            }
        }
        let colour = if p.kept_srt { [0.5; 3] } else { [1.0; 3] };
        for d in -4..=4i64 {
            canvas.blend(centre.0 as i64 + d, centre.1 as i64, colour, 1.0);
            canvas.blend(centre.0 as i64, centre.1 as i64 + d, colour, 1.0);
        }
    }
    canvas.image
}
