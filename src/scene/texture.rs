//! Textures (Mitsuba 3's `checkerboard` and `bitmap`): what varies a material's parameters
//! over a surface (how a textured material is evaluated at a hit: [`super::MaterialAt`]).

use crate::image::srgb;
use glam::{Affine2, Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The most texels a bitmap may hold (16384²: 3 GiB of linear RGB), so that a typo or a
/// hostile file fails with a message instead of exhausting memory.
pub const MAX_TEXELS: u64 = 1 << 28;

/// Why an image file gives no bitmap texture; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum BitmapError {
    #[error(transparent)]
    Image(#[from] crate::image::ImageError),
    #[error("{}: {width}×{height} texels is not within 1..={MAX_TEXELS}, genpath's limit", path.display())]
    Size {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    #[error("{}: texel ({x}, {y}) is {texel:?}: texels must be finite and non-negative", path.display())]
    Texel {
        path: PathBuf,
        x: usize,
        y: usize,
        texel: [f32; 3],
    },
}

/// How a bitmap's texels are looked up (Mitsuba's `filter_type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    Bilinear,
}

/// What a bitmap's lookups outside [0, 1]² read (Mitsuba's `wrap_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Mirror,
    Clamp,
}

/// A bitmap texture: linear RGB texels (row 0 at `v = 0`, the image's top), looked up as
/// Mitsuba 3's `bitmap` looks them up in its RGB variants.
#[derive(Clone, Debug, PartialEq)]
pub struct Bitmap {
    width: u32,
    height: u32,
    /// Row-major, linear (sRGB-decoded unless `raw`).
    texels: Vec<[f32; 3]>,
    filter: Filter,
    wrap: Wrap,
    to_uv: Affine2,
    /// The texels' mean luminance (Mitsuba's `mean()`).
    mean: f32,
}

/// Rec. 709 luminance of a linear RGB colour (Mitsuba's `luminance`).
pub fn luminance(c: Vec3) -> f32 {
    c.x * 0.212_671 + c.y * 0.715_160 + c.z * 0.072_169
}

impl Bitmap {
    /// The texture of `width × height` linear texels (row 0 at the top), which must be
    /// non-empty and match the size.
    pub fn new(
        width: u32,
        height: u32,
        texels: Vec<[f32; 3]>,
        (filter, wrap, to_uv): (Filter, Wrap, Affine2),
    ) -> Self {
        assert!(width > 0 && height > 0);
        assert_eq!(texels.len() as u64, u64::from(width) * u64::from(height));
        let sum: f64 = texels
            .iter()
            .map(|t| f64::from(luminance(Vec3::from(*t))))
            .sum();
        let mean = (sum / texels.len() as f64) as f32;
        Self {
            width,
            height,
            texels,
            filter,
            wrap,
            to_uv,
            mean,
        }
    }

    /// The bitmap of the image file at `path` (read by [`crate::image::read_encoded`]), its
    /// integer formats' values sRGB-decoded unless `raw` (float formats' are linear), looked
    /// up by `lookup`. The error names the file: unreadable, beyond [`MAX_TEXELS`], or with
    /// a texel that is not finite or negative.
    pub fn read(
        path: &Path,
        raw: bool,
        lookup: (Filter, Wrap, Affine2),
    ) -> Result<Self, BitmapError> {
        let (image, encoded) = crate::image::read_encoded(path)?;
        let texels = u64::from(image.width) * u64::from(image.height);
        if texels > MAX_TEXELS || texels == 0 {
            return Err(BitmapError::Size {
                path: path.to_path_buf(),
                width: image.width,
                height: image.height,
            });
        }
        let mut pixels = image.pixels;
        if let Some(i) = pixels
            .iter()
            .position(|t| t.iter().any(|c| !(c.is_finite() && *c >= 0.0)))
        {
            let w = image.width as usize;
            return Err(BitmapError::Texel {
                path: path.to_path_buf(),
                x: i % w,
                y: i / w,
                texel: pixels[i],
            });
        }
        if encoded && !raw {
            decode_srgb(&mut pixels);
        }
        Ok(Self::new(image.width, image.height, pixels, lookup))
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The texel index along an axis of `n` texels for the integer coordinate `i`.
    fn wrap(&self, i: i64, n: u32) -> usize {
        let n = i64::from(n);
        let j = match self.wrap {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m >= n {
                    2 * n - 1 - m
                } else {
                    m
                }
            }
        };
        j as usize
    }

    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let (x, y) = (self.wrap(x, self.width), self.wrap(y, self.height));
        Vec3::from(self.texels[y * self.width as usize + x])
    }

    /// The colour at texture coordinates `uv` (before `to_uv`).
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        let uv = self.to_uv.transform_point2(uv);
        let res = Vec2::new(self.width as f32, self.height as f32);
        // Floats beyond i64 (or NaN) saturate: the wrap still gives a texel.
        match self.filter {
            Filter::Nearest => {
                let p = (uv * res).floor();
                self.texel(p.x as i64, p.y as i64)
            }
            Filter::Bilinear => {
                let p = uv * res - 0.5;
                let i = p.floor();
                let w1 = p - i;
                let w0 = Vec2::ONE - w1;
                let (x, y) = (i.x as i64, i.y as i64);
                let c0 = self.texel(x, y) * w0.x + self.texel(x + 1, y) * w1.x;
                let c1 = self.texel(x, y + 1) * w0.x + self.texel(x + 1, y + 1) * w1.x;
                c0 * w0.y + c1 * w1.y
            }
        }
    }

    /// Mitsuba's `eval_1_grad`: the gradient in texture coordinates `uv` (before `to_uv`) of
    /// the bilinear interpolation of the texels' luminance; zero for nearest lookups.
    pub fn gradient(&self, uv: Vec2) -> Vec2 {
        if self.filter == Filter::Nearest {
            return Vec2::ZERO;
        }
        let res = Vec2::new(self.width as f32, self.height as f32);
        let p = self.to_uv.transform_point2(uv) * res - 0.5;
        let i = p.floor();
        let w1 = p - i;
        let w0 = Vec2::ONE - w1;
        let (x, y) = (i.x as i64, i.y as i64);
        let f = |dx, dy| luminance(self.texel(x + dx, y + dy));
        let (f00, f10, f01, f11) = (f(0, 0), f(1, 0), f(0, 1), f(1, 1));
        let dx = w0.y * (f10 - f00) + w1.y * (f11 - f01);
        let dy = w0.x * (f01 - f00) + w1.x * (f11 - f10);
        // The partials in u and v: through the transpose of to_uv's linear part.
        let m = self.to_uv.matrix2;
        Vec2::new(
            m.x_axis.x * dx + m.x_axis.y * dy,
            m.y_axis.x * dx + m.y_axis.y * dy,
        ) * res
    }
}

/// Mitsuba's `checkerboard` with constant colours: `color0` where the fractional parts of
/// `u` and `v` (after `to_uv`) are both above or both at most 1/2, else `color1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkerboard {
    pub color0: Vec3,
    pub color1: Vec3,
    pub to_uv: Affine2,
}

impl Checkerboard {
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        if self.first_colour(uv) {
            self.color0
        } else {
            self.color1
        }
    }

    /// Mitsuba 3.9.1's `eval_1` of the checkerboard (what a `mask` reads its opacity by), for
    /// grey colours: the other colour than [`Self::eval`]'s, `color1` where both fractional
    /// parts are above or both at most 1/2 (measured: at `uv` (0.25, 0.25) its `eval` gives
    /// `color0`, its `eval_1` `color1`).
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        if self.first_colour(uv) {
            self.color1.x
        } else {
            self.color0.x
        }
    }

    /// Whether `eval` gives `color0` at `uv`.
    fn first_colour(&self, uv: Vec2) -> bool {
        let uv = self.to_uv.transform_point2(uv);
        let f = uv - uv.floor();
        (f.x > 0.5) == (f.y > 0.5)
    }
}

/// A spectrum-valued texture.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Checkerboard(Checkerboard),
    Bitmap(Arc<Bitmap>),
}

impl Texture {
    /// The texture's colour at texture coordinates `uv`.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::Checkerboard(c) => c.eval(uv),
            Texture::Bitmap(b) => b.eval(uv),
        }
    }

    /// Mitsuba's `mean()`: the checkerboard's colours' mean channel values averaged, a
    /// bitmap's mean luminance.
    pub fn mean(&self) -> f32 {
        match self {
            Texture::Checkerboard(c) => {
                0.5 * (c.color0.element_sum() + c.color1.element_sum()) / 3.0
            }
            Texture::Bitmap(b) => b.mean,
        }
    }

    /// The smallest value channel `c` (0, 1, 2: red, green, blue) can return.
    pub fn channel_min(&self, c: usize) -> f32 {
        match self {
            Texture::Checkerboard(k) => k.color0[c].min(k.color1[c]),
            Texture::Bitmap(b) => b.texels.iter().fold(f32::INFINITY, |m, t| m.min(t[c])),
        }
    }

    /// Whether every texel or colour is grey (its three channels equal).
    pub fn is_grey(&self) -> bool {
        let grey = |c: Vec3| c.x == c.y && c.y == c.z;
        match self {
            Texture::Checkerboard(c) => grey(c.color0) && grey(c.color1),
            Texture::Bitmap(b) => b.texels.iter().all(|t| grey(Vec3::from(*t))),
        }
    }

    /// The largest and smallest channel value the texture can return (bilinear lookups
    /// stay within their texels').
    pub fn range(&self) -> (f32, f32) {
        match self {
            Texture::Checkerboard(c) => (
                c.color0.min_element().min(c.color1.min_element()),
                c.color0.max_element().max(c.color1.max_element()),
            ),
            Texture::Bitmap(b) => b
                .texels
                .iter()
                .fold((f32::INFINITY, 0.0f32), |(lo, hi), t| {
                    let t = Vec3::from(*t);
                    (lo.min(t.min_element()), hi.max(t.max_element()))
                }),
        }
    }
}

/// The sRGB-encoded values `encoded` decoded to linear ones.
pub fn decode_srgb(texels: &mut [[f32; 3]]) {
    for t in texels {
        *t = t.map(srgb::decode);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bitmap(filter: Filter, wrap: Wrap) -> Bitmap {
        // Two texels in a row: black, white.
        Bitmap::new(
            2,
            1,
            vec![[0.0; 3], [1.0; 3]],
            (filter, wrap, Affine2::IDENTITY),
        )
    }

    #[test]
    fn nearest_lookups_wrap_as_mitsuba() {
        let at = |w, u: f32| bitmap(Filter::Nearest, w).eval(Vec2::new(u, 0.5)).x;
        let us = [-1.25, -0.75, -0.25, 0.25, 0.75, 1.25, 1.75, 2.25];
        // Mitsuba 3.9.1's values.
        let mirror = [1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0];
        let repeat = [1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0];
        let clamp = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        for (u, (m, (r, c))) in us.iter().zip(mirror.iter().zip(repeat.iter().zip(clamp))) {
            assert_eq!(at(Wrap::Mirror, *u), *m, "mirror {u}");
            assert_eq!(at(Wrap::Repeat, *u), *r, "repeat {u}");
            assert_eq!(at(Wrap::Clamp, *u), c, "clamp {u}");
        }
    }

    #[test]
    fn bilinear_lookups_interpolate_between_texel_centres() {
        let b = bitmap(Filter::Bilinear, Wrap::Clamp);
        assert_eq!(b.eval(Vec2::new(0.5, 0.5)).x, 0.5);
        assert_eq!(b.eval(Vec2::new(0.25, 0.5)).x, 0.0);
        assert_eq!(b.eval(Vec2::new(0.625, 0.5)).x, 0.75);
        let r = bitmap(Filter::Bilinear, Wrap::Repeat);
        // Between the last texel and the first again.
        assert_eq!(r.eval(Vec2::new(1.0, 0.5)).x, 0.5);
        assert_eq!(b.mean, 0.5 * luminance(Vec3::ONE));
    }

    #[test]
    fn the_checkerboard_alternates_by_halves() {
        let c = Checkerboard {
            color0: Vec3::X,
            color1: Vec3::Y,
            to_uv: Affine2::IDENTITY,
        };
        assert_eq!(c.eval(Vec2::new(0.25, 0.25)), Vec3::X);
        assert_eq!(c.eval(Vec2::new(0.75, 0.75)), Vec3::X);
        assert_eq!(c.eval(Vec2::new(0.75, 0.25)), Vec3::Y);
        assert_eq!(c.eval(Vec2::new(-0.25, 0.25)), Vec3::Y);
        assert_eq!(Texture::Checkerboard(c).mean(), 1.0 / 3.0);
    }

    #[test]
    fn the_gradient_is_the_bilinear_interpolants_and_follows_to_uv() {
        // Luminances 0, 1 along x, 0, 0 in the next row: a 2 × 2 bitmap, clamped.
        let texels = vec![[0.0; 3], [1.0; 3], [0.0; 3], [0.0; 3]];
        let lookup = |to_uv| (Filter::Bilinear, Wrap::Clamp, to_uv);
        let b = Bitmap::new(2, 2, texels.clone(), lookup(Affine2::IDENTITY));
        // On the top row's centres (v = 0.25), halfway between them: d/du of the
        // interpolant is (1 − 0) per texel, d/dv (0 − 1/2) per texel, times 2 texels per unit.
        let g = b.gradient(Vec2::new(0.5, 0.25));
        assert!((g - Vec2::new(2.0, -1.0)).length() < 1e-5, "{g}");
        // Halfway down, the rows mix: d/du halves, d/dv is −(1/2) per texel.
        let g = b.gradient(Vec2::new(0.5, 0.5));
        assert!((g - Vec2::new(1.0, -1.0)).length() < 1e-5, "{g}");
        // With u scaled by 3 in to_uv, d/du triples (the lookup moving with it).
        let scaled = Bitmap::new(
            2,
            2,
            texels.clone(),
            lookup(Affine2::from_scale(Vec2::new(3.0, 1.0))),
        );
        let g = scaled.gradient(Vec2::new(0.5 / 3.0, 0.25));
        assert!((g - Vec2::new(6.0, -1.0)).length() < 1e-5, "{g}");
        // Nearest lookups: zero.
        let nearest = Bitmap::new(
            2,
            2,
            texels,
            (Filter::Nearest, Wrap::Clamp, Affine2::IDENTITY),
        );
        assert_eq!(nearest.gradient(Vec2::new(0.5, 0.5)), Vec2::ZERO);
    }
}
