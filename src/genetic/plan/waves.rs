//! Scheduling the GA pixels: the [`Waves`] they evolve in past the pilot (the baseline, the
//! pilot going on, then cold and warm-started waves, in chunks under a time limit).

use super::super::individual::Individual;
use super::baseline::baseline_choice;
use super::context::{GaRun, PixelContext};
use super::pixel::run_pixel;
use super::stages::{LearnStore, PlanError, StoreError, WaveEntry};
use super::types::{Evolved, Origin, PlanFor, PlanStats};
use crate::film::PixelSums;
use crate::progress::progress_bar;
use indicatif::ProgressBar;
use rayon::prelude::*;
use std::time::Instant;

/// How often a store keeps a wave's new results while the wave is evolved (besides at
/// once after its first chunk, at its end and on a stop): each keep rewrites the job's
/// file of the wave, so keeping every chunk would write a large wave's results many times.
/// A job killed outright (SIGKILL, a node lost) loses at most this much work.
const KEEP_EVERY: std::time::Duration = std::time::Duration::from_secs(10);

/// A GA pixel to evolve (an index into [`Waves::chosen`]) and how.
pub(super) struct Job {
    pub(super) pixel: usize,
    pub(super) run: GaRun,
}

impl Job {
    /// From random individuals, for `generations`, on the pixel's first GA stream.
    fn cold(pixel: usize, generations: usize, trial: bool) -> Self {
        let run = GaRun {
            seeds: Vec::new(),
            generations,
            stream: 0,
            trial,
        };
        Self { pixel, run }
    }
}

/// A plan's GA pixels as they are chosen and evolved, wave by wave (each wave in parallel
/// on the current rayon pool), with the progress bar.
pub(super) struct Waves<'a> {
    pub(super) context: &'a PixelContext<'a>,
    bar: ProgressBar,
    /// The GA pixels in the order chosen: the pilot's, then the baseline's others.
    pub(super) chosen: Vec<(u32, u32, Origin)>,
    /// Each chosen pixel's result, once evolved.
    pub(super) done: Vec<Option<Evolved>>,
    /// The first `pilot` of `chosen`, evolved before the gate decides on the others.
    pub(super) pilot: usize,
    /// The pilot pixels' scouting runs that the pixels going on from them replaced (their
    /// work still counts in the stats).
    scouted: Vec<Evolved>,
    /// GA pixels the time limit left out (indices into `chosen`).
    late: Vec<usize>,
    /// When the plan began: `PlanConfig::time_limit` counts from here.
    start: Instant,
    /// Waves evolved so far: the next one's number in the store.
    wave: usize,
}

impl<'a> Waves<'a> {
    /// The waves of a plan begun at `start`, with `pilot` (none without the gate) chosen
    /// first; a progress bar on stderr when `progress`.
    pub(super) fn new(
        context: &'a PixelContext<'a>,
        pilot: Vec<(u32, u32, Origin)>,
        progress: bool,
        start: Instant,
    ) -> Self {
        let n = pilot.len();
        Self {
            context,
            bar: progress_bar(n as u64, "GA", progress),
            chosen: pilot,
            done: vec![None; n],
            pilot: n,
            scouted: Vec::new(),
            late: Vec::new(),
            start,
            wave: 0,
        }
    }

    /// The chosen pixels' positions.
    fn positions(&self) -> Vec<(u32, u32)> {
        self.chosen.iter().map(|&(x, y, _)| (x, y)).collect()
    }

    /// Chooses `pixels` too, except those at `keep` (already chosen).
    fn add(&mut self, pixels: &[(u32, u32, Origin)], keep: &[(u32, u32)]) {
        self.chosen
            .extend((pixels.iter()).filter(|&&(x, y, _)| !keep.contains(&(x, y))));
        let n = self.chosen.len();
        self.done.resize(n, None);
        self.bar.inc_length((n - self.pilot) as u64);
    }

    /// Evolves chosen pixel `i` as `run` says.
    pub(super) fn evolve_one(&self, i: usize, run: &GaRun) -> Evolved {
        let r = run_pixel(self.context, self.chosen[i], run);
        self.bar.inc(1);
        r
    }

    /// Evolves a wave's pixels in parallel, or, with a store, takes those it holds and
    /// evolves this job's share of the rest, keeping them there.
    pub(super) fn evolve(&mut self, wave: &[Job]) -> Result<(), PlanError> {
        let number = self.wave;
        self.wave += 1;
        if let Some(store) = self.context.store {
            return self.evolve_stored(store, number, wave);
        }
        let this = &*self;
        let results: Vec<(usize, Evolved)> = wave
            .par_iter()
            .map(|job| (job.pixel, this.evolve_one(job.pixel, &job.run)))
            .collect();
        for (i, r) in results {
            self.done[i] = Some(r);
        }
        Ok(())
    }

    /// [`Self::evolve`] through `store`: the wave's results it holds, then this job's share
    /// of the others in chunks, each kept as it finishes, so that a signal loses at most
    /// one chunk's pixels in flight. Stops with [`PlanError::ShareDone`] where other jobs'
    /// shares are missing, and with [`PlanError::Stopped`] on a signal.
    fn evolve_stored(
        &mut self,
        store: &dyn LearnStore,
        number: usize,
        wave: &[Job],
    ) -> Result<(), PlanError> {
        if wave.is_empty() {
            return Ok(());
        }
        let mut found: Vec<Option<Evolved>> = vec![None; wave.len()];
        for e in store.load(number).map_err(PlanError::Store)? {
            let job = e.job as usize;
            let Some(expected) = wave.get(job).map(|j| self.chosen[j.pixel]) else {
                return Err(PlanError::Store(StoreError(format!(
                    "wave {number} has {} GA pixels, and a stored result is for its job {job}",
                    wave.len()
                ))));
            };
            if (e.pixel.x, e.pixel.y) != (expected.0, expected.1) {
                return Err(PlanError::Store(StoreError(format!(
                    "wave {number}, job {job}: the stored result is for pixel ({}, {}), this \
                     plan's job is pixel ({}, {})",
                    e.pixel.x, e.pixel.y, expected.0, expected.1
                ))));
            }
            let mut pixel = e.pixel;
            pixel.best = e.best;
            found[job].get_or_insert((pixel, e.counts));
        }
        let todo: Vec<usize> = (0..wave.len())
            .filter(|&k| found[k].is_none() && store.mine(k))
            .collect();
        let chunk = 4 * rayon::current_num_threads();
        let mut evolved = 0;
        // Results not yet kept, and when they were last kept (`None`: never, so that the
        // first chunk is kept at once and an unwritable store fails early).
        let mut pending: Vec<WaveEntry> = Vec::new();
        let mut kept_at: Option<Instant> = None;
        for (i, c) in todo.chunks(chunk).enumerate() {
            let this = &*self;
            let results: Vec<(usize, Evolved)> = c
                .par_iter()
                .filter(|_| store.stop_requested().is_none())
                .map(|&k| (k, this.evolve_one(wave[k].pixel, &wave[k].run)))
                .collect();
            pending.extend(results.iter().map(|(k, (pixel, counts))| WaveEntry {
                job: *k as u32,
                pixel: pixel.clone(),
                best: pixel.best.clone(),
                counts: *counts,
            }));
            evolved += results.len();
            for (k, r) in results {
                found[k] = Some(r);
            }
            let stop = store.stop_requested();
            let last = (i + 1) * chunk >= todo.len();
            let due = kept_at.is_none_or(|t| t.elapsed() >= KEEP_EVERY);
            if !pending.is_empty() && (stop.is_some() || last || due) {
                store
                    .save(number, wave.len(), &pending)
                    .map_err(PlanError::Store)?;
                pending.clear();
                kept_at = Some(Instant::now());
            }
            if let Some(signal) = stop {
                return Err(PlanError::Stopped {
                    signal,
                    wave: number,
                    done: found.iter().flatten().count(),
                    jobs: wave.len(),
                });
            }
        }
        let missing = found.iter().filter(|f| f.is_none()).count();
        if missing > 0 {
            return Err(PlanError::ShareDone {
                wave: Some(number),
                evolved,
                missing,
            });
        }
        for (job, r) in wave.iter().zip(found) {
            self.done[job.pixel] = r;
        }
        Ok(())
    }

    /// Evolves `jobs` as a wave; with a time limit in chunks, each only if time is left
    /// (the others are late).
    fn evolve_in_chunks(&mut self, jobs: &[Job]) -> Result<(), PlanError> {
        let limit = self.context.config.time_limit;
        let chunk = match limit {
            Some(_) => 4 * rayon::current_num_threads(),
            None => usize::MAX,
        };
        for c in jobs.chunks(chunk) {
            if limit.is_some_and(|limit| self.start.elapsed().as_secs_f64() >= limit) {
                self.late.extend(c.iter().map(|j| j.pixel));
            } else {
                self.evolve(c)?;
            }
        }
        Ok(())
    }

    /// Past a pilot that pays, or without the gate: the baseline, which chooses the other GA
    /// pixels (the pilot's stay, whatever their cells' variance), then [`Self::evolve_rest`].
    /// The low-variance cells' pixels go to `fallback_points`, and with the gate, for a
    /// mixture, the late ones too. Returns the baseline's seconds and samples.
    pub(super) fn past_pilot(
        &mut self,
        cells: &[Option<(u32, u32)>],
        scout: usize,
        stats: &mut PlanStats,
        fallback_points: &mut Vec<(u32, u32)>,
    ) -> Result<(f64, PixelSums), PlanError> {
        let t2 = Instant::now();
        let keep = self.positions();
        let (choice, samples) = baseline_choice(self.context, cells, &keep, stats);
        let gate = self.context.gate;
        fallback_points.extend(&choice.low);
        self.add(&choice.pixels, &keep);
        let baseline_part = t2.elapsed().as_secs_f64();
        let late = self.evolve_rest(scout)?;
        stats.time_limited_pixels = late.len();
        // A mixture's variance can grow fast away from its GA pixel, so with the gate a
        // cell the GA did not reach renders with `pt`. A guide keeps `pt`'s next-event
        // estimation and BRDF sampling: once the pilot showed it pays, such a cell takes
        // its evolved neighbours' guides, as without the gate: sending those cells to `pt`
        // made the image worse where the time limit leaves many GA pixels out
        // (reports/README.md, "Measurements formerly in code comments (2026-12-07)",
        // `Waves::past_pilot`).
        if gate && self.context.plan_for == PlanFor::Mixture {
            let chosen = &self.chosen;
            fallback_points.extend(late.iter().map(|&i| (chosen[i].0, chosen[i].1)));
        }
        Ok((baseline_part, samples))
    }

    /// Past a pilot that does not pay: no baseline, and every other cell's pixel in `grid`
    /// goes to `fallback_points`.
    pub(super) fn leave_to_pt(
        &self,
        grid: &[(u32, u32)],
        stats: &mut PlanStats,
        fallback_points: &mut Vec<(u32, u32)>,
    ) {
        stats.gated_pixels = grid.len() - self.done.iter().flatten().count();
        let pilot_at = self.positions();
        fallback_points.extend((grid.iter()).filter(|at| !pilot_at.contains(at)));
    }

    /// Once the pilot (scouted for `scout` generations) pays, or without the gate: the pilot
    /// goes on, then the other chosen pixels evolve. With warm starts, the grid pixels of
    /// "white" cells (in a checkerboard of cells) first, then the rest, seeded from their
    /// evolved neighbours. Returns the pixels the time limit left out.
    fn evolve_rest(&mut self, scout: usize) -> Result<Vec<usize>, PlanError> {
        let config = self.context.config;
        let g = config.grid(self.context.plan_for);
        let white = |i: usize| {
            let (x, y, origin) = self.chosen[i];
            origin == Origin::Grid && (x / g + y / g) % 2 == 0
        };
        let (first, second): (Vec<usize>, Vec<usize>) =
            (self.pilot..self.chosen.len()).partition(|&i| !config.warm_start || white(i));
        self.go_on(scout)?;
        // For a mixture every GA pixel runs the gate's trial; for a guide only the pilot
        // (see the module documentation).
        let trial = self.context.plan_for == PlanFor::Mixture;
        let generations = self.context.ga.generations;
        let cold: Vec<Job> = first
            .iter()
            .map(|&i| Job::cold(i, generations, trial))
            .collect();
        self.evolve_in_chunks(&cold)?;
        let second = self.warm_wave(&second, trial);
        self.evolve_in_chunks(&second)?;
        Ok(std::mem::take(&mut self.late))
    }

    /// The pilot goes on from each pixel's best individual for the generations its
    /// `scout`ing left, whatever the time limit (the pilot showed the GA pays); its scouting
    /// still counts in the stats. A scout without a best individual (no light-carrying test
    /// path) or without generations left stands as it is.
    fn go_on(&mut self, scout: usize) -> Result<(), PlanError> {
        let rest = self.context.ga.generations.saturating_sub(scout);
        let mut go_on = Vec::new();
        for i in 0..self.pilot {
            let Some((p, counts)) = self.done[i].take() else {
                continue;
            };
            match p.best.clone() {
                Some(best) if rest > 0 => {
                    self.scouted.push((p, counts));
                    let run = GaRun {
                        seeds: vec![best],
                        generations: rest,
                        stream: 1,
                        trial: true,
                    };
                    go_on.push(Job { pixel: i, run });
                }
                _ => self.done[i] = Some((p, counts)),
            }
        }
        self.bar.inc_length(go_on.len() as u64);
        self.evolve(&go_on)
    }

    /// The second wave's jobs: with warm starts, seeds from the pilot and the first wave
    /// only, whatever the chunks, and half the generations.
    fn warm_wave(&self, second: &[usize], trial: bool) -> Vec<Job> {
        let config = self.context.config;
        let generations = self.context.ga.generations;
        let warm = generations.div_ceil(2);
        second
            .iter()
            .map(|&i| match config.warm_start {
                true => {
                    let run = GaRun {
                        seeds: neighbour_seeds(&self.done, self.chosen[i], self.context),
                        generations: warm,
                        stream: 0,
                        trial,
                    };
                    Job { pixel: i, run }
                }
                false => Job::cold(i, generations, trial),
            })
            .collect()
    }

    /// The evolved pixels, in the order chosen, and the pilot's replaced scouting runs.
    pub(super) fn finish(self) -> (Vec<Evolved>, Vec<Evolved>) {
        let results = self.done.into_iter().flatten().collect();
        self.bar.finish_and_clear();
        (results, self.scouted)
    }
}

/// Best individuals of up to [`super::config::PlanConfig::neighbours`] evolved GA pixels nearest to `at`,
/// within two grid spacings: the first generation of a warm-started GA.
pub(super) fn neighbour_seeds(
    done: &[Option<Evolved>],
    (x, y, _): (u32, u32, Origin),
    context: &PixelContext,
) -> Vec<Individual> {
    let config = context.config;
    let reach = 2.0 * config.grid(context.plan_for) as f64;
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
        .take(config.neighbours(context.plan_for))
        .map(|n| n.2.clone())
        .collect()
}
