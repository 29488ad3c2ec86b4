//! Geometry and numerics that know nothing of the renderer: orthonormal bases, a uniform
//! direction, Gauss–Legendre quadrature, a triangle's area, and [`trig`]'s libm-free
//! trigonometry. The bottom layer: every other module may use it, and it uses none of them,
//! so that scenes and acceleration structures share these helpers without reaching up into
//! the samplers.

pub mod alias;
pub mod trig;

use glam::{DVec3, Vec3};

/// A direction uniform over the unit sphere from two uniform numbers in [0, 1) (Mitsuba's
/// `square_to_uniform_sphere`: `z = 1 − 2 u1`, azimuth `2π u2`).
pub fn uniform_sphere(u1: f32, u2: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// An orthonormal basis `(t, b)` completing unit `n` (Duff et al., "Building an Orthonormal
/// Basis, Revisited").
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Gauss–Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence):
/// the microfacet tables' quadrature, and the sampler tests'.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// A point uniform by area in the triangle `[a, b, c]` from two uniform numbers in [0, 1)
/// (the square-root warp).
pub fn uniform_in_triangle([a, b, c]: [DVec3; 3], u1: f64, u2: f64) -> DVec3 {
    let su = u1.sqrt();
    let (b1, b2) = (su * (1.0 - u2), su * u2);
    a * (1.0 - su) + b * b1 + c * b2
}

/// The area of the triangle `[a, b, c]`, in `f64`.
pub fn triangle_area([a, b, c]: [Vec3; 3]) -> f64 {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    0.5 * (b - a).cross(c - a).length()
}
