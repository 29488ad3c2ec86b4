//! Mitsuba's transform operations (`include/mitsuba/core/transform.h`), in `f64`. A
//! `<transform>` lists them in the order they apply: `M = op_n ⋯ op_1`.

use glam::{DMat4, DVec3, DVec4};

/// A rotation by `degrees` about `axis` (right-handed; the axis is normalised), `None` for
/// a zero axis.
pub fn rotate(axis: DVec3, degrees: f64) -> Option<DMat4> {
    let axis = axis.try_normalize()?;
    Some(DMat4::from_axis_angle(axis, degrees.to_radians()))
}

/// A matrix from 16 (4×4) or 9 (the linear 3×3 part) values, row after row.
pub fn matrix(values: &[f64]) -> Option<DMat4> {
    match values.len() {
        16 => Some(DMat4::from_cols_slice(values).transpose()),
        9 => {
            let r = |i: usize| DVec4::new(values[3 * i], values[3 * i + 1], values[3 * i + 2], 0.0);
            Some(DMat4::from_cols(r(0), r(1), r(2), DVec4::W).transpose())
        }
        _ => None,
    }
}

/// Mitsuba's `look_at`: columns (left, up', dir, origin) with `dir = normalize(target −
/// origin)`, `left = normalize(up × dir)`, `up' = dir × left`, so that the camera's local +x
/// points to the image's left. A zero `up` is replaced by Mitsuba's `coordinate_system(dir)`.
/// `None` where the frame is not finite (`target = origin`, `up ∥ dir`).
pub fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (target - origin).normalize();
    let up = if up == DVec3::ZERO {
        coordinate_system(dir)
    } else {
        up
    };
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    let m = DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    );
    m.is_finite().then_some(m)
}

/// The first tangent of Mitsuba's `coordinate_system(n)` (Duff et al. 2017).
fn coordinate_system(n: DVec3) -> DVec3 {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    DVec3::new(
        (n.x * n.x * a).mul_add(sign, 1.0),
        n.x * n.y * a * sign,
        -n.x * sign,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operations_compose_first_listed_first() {
        // translate then rotate 90° about z: (1,0,0) → (1,0,0)+(0,1,0)... applied to origin.
        let m = rotate(DVec3::Z, 90.0).unwrap() * DMat4::from_translation(DVec3::X);
        let p = m.transform_point3(DVec3::ZERO);
        assert!((p - DVec3::Y).length() < 1e-12, "{p}");
        assert!(rotate(DVec3::ZERO, 10.0).is_none());
    }

    #[test]
    fn matrix_is_row_major() {
        let m = matrix(&[
            1., 0., 0., 5., 0., 1., 0., 6., 0., 0., 1., 7., 0., 0., 0., 1.,
        ])
        .unwrap();
        assert_eq!(m.transform_point3(DVec3::ZERO), DVec3::new(5.0, 6.0, 7.0));
        let r = matrix(&[0., -1., 0., 1., 0., 0., 0., 0., 1.]).unwrap();
        assert!((r.transform_vector3(DVec3::X) - DVec3::Y).length() < 1e-12);
        assert!(matrix(&[1.0; 4]).is_none());
    }

    #[test]
    fn look_at_points_local_x_left() {
        // Looking down −z with +y up: the image's right is +x, so local +x maps to −x.
        let m = look_at(DVec3::new(0., 0., 5.), DVec3::ZERO, DVec3::Y).unwrap();
        assert!((m.transform_vector3(DVec3::X) + DVec3::X).length() < 1e-12);
        assert!((m.transform_vector3(DVec3::Z) + DVec3::Z).length() < 1e-12);
        assert!((m.transform_vector3(DVec3::Y) - DVec3::Y).length() < 1e-12);
        assert!(look_at(DVec3::ZERO, DVec3::ZERO, DVec3::Y).is_none());
        assert!(look_at(DVec3::ZERO, DVec3::Y, DVec3::Y).is_none());
        let auto = look_at(DVec3::ZERO, DVec3::Z, DVec3::ZERO).unwrap();
        assert!(auto.is_finite());
    }
}
