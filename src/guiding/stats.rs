//! What training a [`SpatialField`] did, as the render's statistics report it: its
//! [`FieldStats`], with the GA trial's outcome ([`GuidesTrial`]) where `ga-pt` ran one.
//!
//! [`GuidesTrial`] is the result of a trial that `integrators::pg` runs, but it is kept here,
//! beside the statistics that hold it: the render writes the field's statistics as they
//! are, the trial's outcome among them, and guiding imports nothing from the integrators
//! (they import guiding).
//!
//! [`SpatialField`]: super::SpatialField

/// What training a spatial guide (a [`SpatialField`](super::SpatialField)) did.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct FieldStats {
    /// Training passes (pass `i`: `2^i` path-traced samples per pixel), and their samples
    /// per pixel in all (part of the image).
    pub passes: u32,
    pub spp: u32,
    /// Records carrying light, over all passes (each guide learns from its pass's alone).
    pub records: usize,
    /// Leaves of the spatial trees (one tree per facing), and those with a directional
    /// quadtree.
    pub cells: usize,
    pub trained_cells: usize,
    /// Nodes of all directional quadtrees.
    pub directional_nodes: usize,
    /// Lattice cells (per facing) where next-event estimation runs at
    /// [`DARK_LIGHT_SHARE`](super::field::DARK_LIGHT_SHARE).
    pub dark_cells: usize,
    /// Where the last guide learned its share of guided sampling per region
    /// (`--guide-selection learned`): what it learned.
    pub selection: Option<SelectionStats>,
    /// Wall-clock seconds of the training passes.
    pub seconds: f64,
    /// With a GA plan's per-pixel guides: the last training pass's trial of them against
    /// this guide alone, which left them beside it or not.
    pub guides_trial: Option<GuidesTrial>,
}

/// A training pass's trial of a GA plan's per-pixel guides against this guide alone: the
/// mean relative variance of a sample (variance over `mean² + 0.01`, as relMSE weighs
/// errors) times the mean cost of a sample in rays, over the pixels the plan guides,
/// against that over the control arm, the one pixel in sixteen that the pass leaves to this
/// guide alone.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GuidesTrial {
    /// The training pass that ran the trial.
    pub pass: u32,
    /// Pixels in each arm.
    pub guided_pixels: usize,
    pub control_pixels: usize,
    /// Mean relative variance times mean cost per sample of the guided arm over the control
    /// arm's.
    pub ratio: f64,
    /// Whether the plan's guides stayed (for the later passes and the render).
    pub kept: bool,
}

/// What a field learned of its shares of guided sampling (`super::selection`): how many
/// regions fitted theirs, how many of those sit at each bound, and a histogram of the
/// fitted shares in eight equal bins between the bounds (regions, and their records).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SelectionStats {
    pub regions: usize,
    pub fitted: usize,
    pub at_min: usize,
    pub at_max: usize,
    /// The fitted shares' mean, over regions and over records.
    pub mean: f64,
    pub mean_per_record: f64,
    pub histogram: [usize; 8],
    pub histogram_records: [usize; 8],
}
