//! The training records (Open PGL's `SampleStorage`): what a training pass recorded, over
//! the scene's box, and which lattice cells its light samples found dark; a
//! [`SpatialField`] is built from them ([`SampleStorage::field`]).

use super::field::{GuideStateError, SpatialField};
use super::lattice::{Lattice, FACINGS};
use super::selection::SelectionRecord;
use crate::accel::TriangleMesh;
use glam::Vec3;

/// A lattice cell turns dark after this many light samples in one pass, none of which
/// reached a light (had the light been visible to one in ten of them, the chance of that
/// would be 0.9^32 = 3 %).
pub const DARK_AFTER_TRIES: u32 = 32;

/// The bit of a light try that says it reached a light (set by the recorder, read where
/// the cells' darkness is updated).
pub(super) const REACHED: u32 = 1 << 31;

/// One training record: where, which way the surface there faces (see
/// [`facing`](super::lattice::facing)), the direction on the square
/// ([`to_square`](super::square::to_square)), and the cosine-weighted radiance over the
/// direction's density (luminance).
#[derive(Clone, Copy, Debug)]
pub struct Record {
    pub p: Vec3,
    pub facing: u8,
    pub dir: [f32; 2],
    pub value: f32,
}

/// Training records over the scene's box, and which cells are dark: what a [`SpatialField`]
/// is built from (`train_spatial` keeps one pass's records at a time).
#[derive(Clone, Debug)]
pub struct SampleStorage {
    lo: Vec3,
    hi: Vec3,
    lattice: Lattice,
    /// (Visible to the recorder, which adds its records and light tries: `add_recorded`.)
    pub(super) records: Vec<Record>,
    /// The light tries added (see `PathSegmentStorage::light_try`).
    pub(super) light_tries: Vec<u32>,
    /// Per facing and lattice cell, whether it is dark: kept from guide to guide.
    dark: Vec<bool>,
    /// Whether the guides learn their share of guided sampling per region
    /// ([`super::selection`]), and the records they learn it from (added as `records`).
    pub(super) learns_selection: bool,
    pub(super) selection: Vec<SelectionRecord>,
}

impl SampleStorage {
    /// No records yet, for a guide over the box `[lo, hi]`.
    pub fn new(lo: Vec3, hi: Vec3) -> Self {
        let lattice = Lattice::new(lo, hi);
        Self {
            lo,
            hi,
            dark: vec![false; FACINGS * lattice.cells()],
            lattice,
            records: Vec::new(),
            light_tries: Vec::new(),
            learns_selection: false,
            selection: Vec::new(),
        }
    }

    /// These records, to learn a share of guided sampling per region with each field
    /// ([`SampleStorage::field`]) when `learn` (`--guide-selection learned`).
    pub fn learning_selection(self, learn: bool) -> Self {
        Self {
            learns_selection: learn,
            ..self
        }
    }

    /// No records yet, for a guide over the bounding box of `mesh`.
    pub fn around(mesh: &TriangleMesh) -> Self {
        let (lo, hi) = mesh.bounds();
        if lo.cmple(hi).all() {
            Self::new(lo, hi)
        } else {
            Self::new(Vec3::ZERO, Vec3::ONE)
        }
    }

    pub fn add(&mut self, records: impl IntoIterator<Item = Record>) {
        self.records.extend(records);
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Forgets the records and light tries, keeping the storage (and which cells are dark).
    /// Per facing and lattice cell, whether it is dark (what a guide keeps of the guides
    /// before it).
    pub fn dark(&self) -> &[bool] {
        &self.dark
    }

    /// Takes `dark` as the cells that are dark (a training kept between processes); refused
    /// when it is not of this storage's lattice.
    pub fn set_dark(&mut self, dark: Vec<bool>) -> Result<(), GuideStateError> {
        if dark.len() != self.dark.len() {
            return Err(GuideStateError::DarkFlags {
                flags: dark.len(),
                cells: self.dark.len(),
            });
        }
        self.dark = dark;
        Ok(())
    }

    pub fn clear(&mut self) {
        self.records.clear();
        self.light_tries.clear();
        self.selection.clear();
    }

    /// Updates which cells are dark from the light tries added: a cell where a try reached
    /// a light is lit; one without is dark after [`DARK_AFTER_TRIES`] tries, and a dark one
    /// stays dark (its tries now taken at
    /// [`DARK_LIGHT_SHARE`](super::field::DARK_LIGHT_SHARE)). The tries are used up, so
    /// that a second field from the same records does not count them again.
    fn update_dark(&mut self) {
        let mut tries = vec![0u32; self.dark.len()];
        let mut reached = vec![false; self.dark.len()];
        for t in self.light_tries.drain(..) {
            let i = (t & !REACHED) as usize;
            tries[i] += 1;
            reached[i] |= t & REACHED != 0;
        }
        for (i, dark) in self.dark.iter_mut().enumerate() {
            *dark = !reached[i] && (*dark || tries[i] >= DARK_AFTER_TRIES);
        }
    }

    /// The field of the records added so far (see [`super::field`]), with the shares of
    /// guided sampling learned per region where the storage learns them. Builds reorder the
    /// records, deterministically.
    pub fn field(&mut self) -> SpatialField {
        self.update_dark();
        let mut field = SpatialField::build(
            &self.lattice,
            (self.lo, self.hi),
            &mut self.records,
            &self.dark,
        );
        if self.learns_selection {
            field.learn_shares(&self.selection);
        }
        field
    }

    /// The lattice that records and light tries are kept on.
    pub(super) fn lattice(&self) -> &Lattice {
        &self.lattice
    }
}

/// A field from records alone, kept here beside the storage it goes through so that
/// `field` need not import the storage that builds it.
impl SpatialField {
    /// The guide trained on `records` alone, over the box `[lo, hi]`.
    pub fn train(lo: Vec3, hi: Vec3, records: impl IntoIterator<Item = Record>) -> Self {
        let mut all = SampleStorage::new(lo, hi);
        all.add(records);
        all.field()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guiding::field::DARK_LIGHT_SHARE;
    use crate::guiding::recorder::PathSegmentStorage;
    use crate::path::pt::PathRecorder;

    /// A cell turns dark after enough light tries of which none reached a light, stays
    /// dark while no try reaches one, and turns lit when one does; a cell with too few tries
    /// stays lit.
    #[test]
    fn cells_turn_dark_where_light_samples_never_arrive() {
        let mut records = SampleStorage::new(Vec3::ZERO, Vec3::ONE);
        let (a, b, c) = (Vec3::splat(0.1), Vec3::splat(0.5), Vec3::splat(0.9));
        let tries = |records: &mut SampleStorage, p: Vec3, n: u32, reached: u32| {
            let mut recorder = PathSegmentStorage::new(records);
            for i in 0..n {
                recorder.light_try(p, Vec3::Y, i < reached);
            }
            records.add_recorded(recorder);
        };
        tries(&mut records, a, DARK_AFTER_TRIES, 0);
        tries(&mut records, b, DARK_AFTER_TRIES, 1);
        tries(&mut records, c, DARK_AFTER_TRIES - 1, 0);
        let guide = records.field();
        let share = |g: &SpatialField, p: Vec3, n: Vec3| g.at(p, n).1;
        assert_eq!(share(&guide, a, Vec3::Y), DARK_LIGHT_SHARE);
        // The other side of the same place was not tried.
        assert_eq!(share(&guide, a, -Vec3::Y), 1.0);
        assert_eq!(share(&guide, b, Vec3::Y), 1.0);
        assert_eq!(share(&guide, c, Vec3::Y), 1.0);
        assert_eq!(guide.stats.dark_cells, 1);
        // The next pass tries the dark cell at its share: a few tries keep it dark ...
        records.clear();
        tries(&mut records, a, 3, 0);
        assert_eq!(share(&records.field(), a, Vec3::Y), DARK_LIGHT_SHARE);
        // ... no try keeps it dark, and one that reaches a light makes it lit.
        records.clear();
        assert_eq!(share(&records.field(), a, Vec3::Y), DARK_LIGHT_SHARE);
        tries(&mut records, a, 3, 1);
        assert_eq!(share(&records.field(), a, Vec3::Y), 1.0);
    }
}
