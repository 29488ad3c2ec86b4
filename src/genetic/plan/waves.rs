//! Scheduling the GA pixels in waves: warm starts from the evolved neighbours' best
//! individuals.

use super::super::individual::Individual;
use super::baseline::Origin;
use super::config::PlanConfig;
use super::pixel::GaPixel;
use crate::path::RayCounts;

/// Best individuals of up to `config.neighbours` evolved GA pixels nearest to `at`, within
/// two grid spacings: the first generation of a warm-started GA.
pub(super) fn neighbour_seeds(
    done: &[Option<(GaPixel, RayCounts)>],
    (x, y, _): (u32, u32, Origin),
    config: &PlanConfig,
) -> Vec<Individual> {
    let reach = 2.0 * config.grid as f64;
    let mut near: Vec<(f64, usize, &Individual)> = done
        .iter()
        .enumerate()
        .filter_map(|(i, d)| {
            let (p, _) = d.as_ref()?;
            let best = p.best.as_ref()?;
            let d = (p.x as f64 - x as f64).hypot(p.y as f64 - y as f64);
            (d <= reach).then_some((d, i, best))
        })
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    near.iter()
        .take(config.neighbours)
        .map(|n| n.2.clone())
        .collect()
}
