//! Where a spatial lookup lands: which way the surface faces ([`facing`]) and the cell of a
//! regular lattice over the scene's box (`Lattice`). The kd-trees of a [`SpatialField`]
//! cut down to a lattice cell at the finest, so that every cell lies in one leaf and a
//! lookup is one read of a per-facing, per-cell table; the training's light tries and dark
//! cells are kept per facing and cell too.
//!
//! [`SpatialField`]: super::SpatialField

use glam::Vec3;

/// Lattice cells along the scene box's longest side: the finest spatial regions (see
/// `Lattice`).
pub const LATTICE_LONGEST: u32 = 16;

/// Which way a surface normal `n` faces: its largest component's axis and sign, `0 … 5`.
/// Each facing has its own spatial tree, so that the two sides of a thin wall (the divider
/// of fig1: lit from above, dark below, a millimetre apart) learn apart.
pub fn facing(n: Vec3) -> usize {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + usize::from(n[axis] < 0.0)
}

/// Ways a normal can face (see [`facing`]).
pub const FACINGS: usize = 6;

/// The regular lattice over the scene's box that spatial lookups go through: the kd-tree's
/// cuts halve boxes down to a lattice cell at the finest, so that every lattice cell lies in
/// one leaf, and a lookup is one table read instead of a descent.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Lattice {
    lo: Vec3,
    /// A cell's size along each axis, and its inverse.
    pub(super) cell: Vec3,
    inv: Vec3,
    pub(super) res: [u32; 3],
}

impl Lattice {
    /// [`LATTICE_LONGEST`] cells along the box's longest side, and along each other side the
    /// power of two that keeps the cells closest to cubes (the kd-tree halves sides).
    pub(super) fn new(lo: Vec3, hi: Vec3) -> Self {
        let size = (hi - lo).max(Vec3::splat(1e-6));
        let longest = size.max_element();
        let res = size.to_array().map(|s| {
            let n = (LATTICE_LONGEST as f32 * s / longest).max(1.0);
            let p = n.log2().round().clamp(0.0, 10.0) as u32;
            1u32 << p
        });
        let cell = size / Vec3::from_array(res.map(|r| r as f32));
        Self {
            lo,
            cell,
            inv: cell.recip(),
            res,
        }
    }

    pub(super) fn cells(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }

    /// The index of the cell of `p` on a surface of normal `n` in a table of all facings'
    /// cells, facing after facing.
    pub(super) fn index_facing(&self, p: Vec3, n: Vec3) -> usize {
        self.index_in(p, facing(n))
    }

    /// The index of the cell of `p` on a surface facing `facing` (see [`facing`]).
    pub(super) fn index_in(&self, p: Vec3, facing: usize) -> usize {
        facing * self.cells() + self.index(p)
    }

    /// The cell of `p` (points outside the box go to the nearest cell).
    fn index(&self, p: Vec3) -> usize {
        let t = ((p - self.lo) * self.inv).to_array();
        // `as u32` maps NaN and negatives to 0.
        let i: [usize; 3] = std::array::from_fn(|a| (t[a] as u32).min(self.res[a] - 1) as usize);
        (i[2] * self.res[1] as usize + i[1]) * self.res[0] as usize + i[0]
    }

    /// The centre of cell `index`.
    pub(super) fn centre(&self, index: usize) -> Vec3 {
        let (r0, r1) = (self.res[0] as usize, self.res[1] as usize);
        let i = [index % r0, index / r0 % r1, index / (r0 * r1)];
        self.lo + self.cell * (Vec3::from_array(i.map(|c| c as f32)) + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facings() {
        let normals = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (i, n) in normals.into_iter().enumerate() {
            assert_eq!(facing(n), i);
            assert_eq!(facing((n + Vec3::splat(0.3)).normalize()), i);
        }
    }
}
