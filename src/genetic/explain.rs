//! `--explain FILE.svg`: what the genetic algorithm learned, drawn over the rendered image.
//!
//! One self-contained SVG: the render (tone-mapped, its 99th luminance percentile to 0.6)
//! enlarged to at least 768 pixels across, and over it, for every GA pixel:
//! * a cross: white where the GA improved on `srt`, grey where `srt` was kept;
//! * a short stroke from the pixel towards where its heaviest evolved generator's first
//!   sampler sends paths (its anchor point, or its patch's centre), as long as that
//!   generator's share of the evolved weight allows: a field of strokes that shows at a
//!   glance where light comes from, without lines across the image;
//! * each anchor point of the generators holding at least [`MIN_SHARE`] of the evolved
//!   weight, as a dot coloured by the path vertex its sampler steers (first, second, …),
//!   its opacity the generator's weight.
//!
//! The patch samplers of the most evolved weight over all GA pixels (at most
//! [`MAX_PATCHES`]) are outlined, each once however many pixels use it. A legend names
//! every mark and counts the GA pixels.

use super::plan::{GaPixel, Plan};
use crate::image::svg::{escape, image_element, png_bytes, PngError};
use crate::image::{srgb, Image};
use crate::path::generator::{DirectionSampler, PathGenerator};
use crate::sampling::patch::PatchSampler;
use crate::scene::Camera;
use std::fmt::Write;

/// Generators lighter than this share of a pixel's evolved weight are not drawn.
pub const MIN_SHARE: f64 = 0.2;
/// The explanation is enlarged to at least this width.
const MIN_WIDTH: u32 = 768;
/// The stroke of a generator that holds all of the evolved weight, in picture pixels.
const STROKE: f32 = 28.0;
/// The patches outlined: those of the most evolved weight over all GA pixels.
const MAX_PATCHES: usize = 8;

/// Colours of the path vertices the samplers steer, in order.
const STEP_COLOURS: [&str; 5] = ["#ffd900", "#00e5ff", "#ff33ff", "#ff8000", "#80ff4d"];
const PATCH_COLOUR: &str = "#3dff7a";
/// The crosses of GA pixels where the GA improved on `srt`, and where `srt` was kept.
const IMPROVED_COLOUR: &str = "#ffffff";
const KEPT_COLOUR: &str = "#8c8c8c";
const ORDINALS: [&str; 5] = ["first", "second", "third", "fourth", "fifth"];

/// The render tone-mapped to `[0, 0.6]` by its 99th luminance percentile.
fn backdrop(image: &Image) -> Image {
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
    let mut out = Image::new(image.width, image.height);
    for y in 0..image.height {
        for x in 0..image.width {
            out.set(x, y, image.get(x, y).map(tone));
        }
    }
    out
}

/// Where a direction sampler sends paths, as a point in space: an anchor, or a patch's
/// centre.
fn target(sampler: &DirectionSampler) -> Option<glam::Vec3> {
    match sampler {
        DirectionSampler::Anchor(a) => Some(a.anchor.as_vec3()),
        DirectionSampler::Patch(p) => Some(p.center.as_vec3()),
        DirectionSampler::Brdf => None,
    }
}

/// The marks of a picture, scaled by `s` from image to picture pixels.
struct Marks<'a> {
    camera: &'a Camera,
    s: f32,
    strokes: String,
    /// The strokes again, uncoloured: drawn first, wider and black, so that they stand out.
    shadows: String,
    dots: String,
    /// Every patch sampler of the drawn generators, with its evolved weight summed over the
    /// GA pixels.
    patches: Vec<(PatchSampler, f64)>,
    /// How many path vertices the drawn anchors steer.
    steps: usize,
}

impl Marks<'_> {
    fn project(&self, p: glam::Vec3) -> Option<(f32, f32)> {
        let (x, y, _) = self.camera.project(p)?;
        Some((x * self.s, y * self.s)).filter(|(x, y)| x.is_finite() && y.is_finite())
    }

    /// The stroke of pixel `centre` towards its heaviest generator's first target.
    fn stroke(&mut self, centre: (f32, f32), g: &PathGenerator, share: f64) {
        let Some(first) = g.steps.first() else {
            return;
        };
        let Some(to) = target(&first.sampler) else {
            return;
        };
        let colour = match first.sampler {
            DirectionSampler::Patch(_) => PATCH_COLOUR,
            _ => STEP_COLOURS[0],
        };
        let Some((tx, ty)) = self.project(to) else {
            return;
        };
        let (dx, dy) = (tx - centre.0, ty - centre.1);
        let length = (dx * dx + dy * dy).sqrt();
        if length.is_nan() || length < 1e-3 {
            return;
        }
        let l = (STROKE * share as f32).max(10.0).min(length);
        let (ex, ey) = (centre.0 + dx / length * l, centre.1 + dy / length * l);
        let _ = writeln!(
            self.shadows,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{ex:.1}" y2="{ey:.1}"/>"#,
            centre.0, centre.1
        );
        let _ = writeln!(
            self.strokes,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{ex:.1}" y2="{ey:.1}" stroke="{colour}"/>"#,
            centre.0, centre.1
        );
    }

    /// The anchors (dots) of generator `g` at `alpha`, and its patches with their weight
    /// `weight`.
    fn samplers(&mut self, g: &PathGenerator, alpha: f64, weight: f64) {
        for (k, step) in g.steps.iter().enumerate() {
            match &step.sampler {
                DirectionSampler::Anchor(a) => {
                    let Some((x, y)) = self.project(a.anchor.as_vec3()) else {
                        continue;
                    };
                    let colour = STEP_COLOURS[k % STEP_COLOURS.len()];
                    let _ = writeln!(
                        self.dots,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="3" fill="{colour}" fill-opacity="{alpha:.2}"/>"#
                    );
                    self.steps = self.steps.max(k + 1);
                }
                DirectionSampler::Patch(p) => match self.patches.iter_mut().find(|e| e.0 == *p) {
                    Some(e) => e.1 += weight,
                    None => self.patches.push((*p, weight)),
                },
                DirectionSampler::Brdf => {}
            }
        }
    }

    /// The outlines of the [`MAX_PATCHES`] patches of the most weight.
    fn patch_outlines(&mut self) -> String {
        self.patches.sort_by(|a, b| b.1.total_cmp(&a.1));
        self.patches.truncate(MAX_PATCHES);
        let mut out = String::new();
        for (p, _) in &self.patches {
            let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(su, sv)| self.project((p.center + su * p.half_u + sv * p.half_v).as_vec3()));
            if let [Some(a), Some(b), Some(c), Some(d)] = corners {
                let points: Vec<String> = [a, b, c, d]
                    .iter()
                    .map(|(x, y)| format!("{x:.1},{y:.1}"))
                    .collect();
                let _ = writeln!(out, r#"<polygon points="{}"/>"#, points.join(" "));
            }
        }
        out
    }

    /// A GA pixel: its stroke, its generators' samplers and its cross.
    fn pixel(&mut self, p: &GaPixel, crosses: &mut String) {
        let centre = ((p.x as f32 + 0.5) * self.s, (p.y as f32 + 0.5) * self.s);
        let evolved: f64 = p.mixture.weights[1..].iter().sum();
        let generators = || p.mixture.generators.iter().zip(&p.mixture.weights).skip(1);
        if let Some((g, &w)) = generators().max_by(|a, b| a.1.total_cmp(b.1)) {
            if evolved > 0.0 {
                self.stroke(centre, g, w / evolved);
            }
        }
        for (g, &w) in generators() {
            if evolved > 0.0 && w >= MIN_SHARE * evolved {
                self.samplers(g, 0.3 + 0.7 * w / evolved, w);
            }
        }
        let colour = if p.kept_srt {
            KEPT_COLOUR
        } else {
            IMPROVED_COLOUR
        };
        let (x, y) = centre;
        let _ = writeln!(
            crosses,
            r#"<path d="M{:.1} {y:.1}h7M{x:.1} {:.1}v7" stroke="{colour}"/>"#,
            x - 3.5,
            y - 3.5
        );
    }
}

/// The legend at the top left: one line per kind of mark, and the counts.
fn legend(out: &mut String, marks: &Marks, plan: &Plan) {
    let improved = plan.pixels.iter().filter(|p| !p.kept_srt).count();
    let mut lines: Vec<(String, String)> = vec![
        (
            format!(r#"<path d="M-4 0h9M0 -4v9" stroke="{IMPROVED_COLOUR}"/>"#),
            format!("GA pixel where the GA improved on srt ({improved})"),
        ),
        (
            format!(r#"<path d="M-4 0h9M0 -4v9" stroke="{KEPT_COLOUR}"/>"#),
            format!(
                "GA pixel where srt was kept ({})",
                plan.pixels.len() - improved
            ),
        ),
        (
            format!(
                r#"<line x1="-6" y1="3" x2="6" y2="-3" stroke="{}" stroke-width="2"/>"#,
                STEP_COLOURS[0]
            ),
            "towards the heaviest generator's first anchor (length: its weight)".into(),
        ),
        (
            format!(
                r#"<line x1="-6" y1="3" x2="6" y2="-3" stroke="{PATCH_COLOUR}" stroke-width="2"/>"#
            ),
            "towards the heaviest generator's first patch (length: its weight)".into(),
        ),
    ];
    for (k, colour) in STEP_COLOURS.iter().enumerate().take(marks.steps) {
        let ordinal = ORDINALS.get(k).copied().unwrap_or("later");
        lines.push((
            format!(r#"<circle r="3" fill="{colour}"/>"#),
            format!("anchor point steering the {ordinal} vertex"),
        ));
    }
    if !marks.patches.is_empty() {
        lines.push((
            format!(
                r#"<rect x="-5" y="-4" width="10" height="8" fill="none" stroke="{PATCH_COLOUR}"/>"#
            ),
            format!(
                "patch sampler, of the {} with the most evolved weight",
                marks.patches.len()
            ),
        ));
    }
    let height = 14 + 16 * lines.len() + 14;
    let _ = writeln!(
        out,
        r#"<g font-family="sans-serif" font-size="12" fill="white"><rect x="6" y="6" width="470" height="{height}" fill="black" fill-opacity="0.7"/>"#
    );
    let _ = writeln!(
        out,
        r#"<text x="14" y="22">{} GA pixels; generators with at least {:.0} % of a pixel's evolved weight</text>"#,
        plan.pixels.len(),
        MIN_SHARE * 100.0
    );
    for (i, (mark, label)) in lines.iter().enumerate() {
        let y = 22 + 16 * (i + 1);
        let _ = writeln!(
            out,
            r#"<g transform="translate(22 {})">{mark}</g><text x="36" y="{y}">{}</text>"#,
            y - 4,
            escape(label)
        );
    }
    out.push_str("</g>\n");
}

/// The explanation of `plan` over `render` (the size of the plan), seen through `camera`:
/// an SVG document.
pub fn svg(camera: &Camera, render: &Image, plan: &Plan) -> Result<String, PngError> {
    let scale = MIN_WIDTH.div_ceil(render.width.max(1)).max(1);
    let (width, height) = (render.width * scale, render.height * scale);
    let backdrop = backdrop(render);
    let png = png_bytes(
        render.width,
        render.height,
        &srgb::encode_image_u8(&backdrop),
    )?;
    let mut marks = Marks {
        camera,
        s: scale as f32,
        strokes: String::new(),
        shadows: String::new(),
        dots: String::new(),
        patches: Vec::new(),
        steps: 0,
    };
    let mut crosses = String::new();
    for p in &plan.pixels {
        marks.pixel(p, &mut crosses);
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    image_element(&mut out, 0, 0, width, height, &png);
    let _ = writeln!(
        out,
        r#"<g fill="none" stroke="{PATCH_COLOUR}" stroke-width="1.5">{}</g>"#,
        marks.patch_outlines()
    );
    let _ = writeln!(out, "<g>{}</g>", marks.dots);
    let _ = writeln!(
        out,
        r#"<g stroke="black" stroke-opacity="0.6" stroke-width="5" stroke-linecap="round">{}</g>"#,
        marks.shadows
    );
    let _ = writeln!(
        out,
        r#"<g stroke-width="2.5" stroke-linecap="round">{}</g>"#,
        marks.strokes
    );
    let _ = writeln!(out, r#"<g stroke-width="1.5">{crosses}</g>"#);
    legend(&mut out, &marks, plan);
    out.push_str("</svg>\n");
    Ok(out)
}
