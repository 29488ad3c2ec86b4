//! Walker's alias table (Vose's construction): a discrete distribution over `n` items drawn
//! in constant time from one uniform number, whose probabilities are exact for the density
//! of what it draws (pbrt-v4's `AliasTable`).

/// A discrete distribution proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    /// Per bin: the probability of keeping the bin's own item, and the item taken otherwise.
    bins: Vec<(f64, u32)>,
    /// The normalised probability of each item.
    pmf: Vec<f64>,
}

impl AliasTable {
    /// The table of `weights` (finite, non-negative); `None` where they sum to nothing (or
    /// to something not finite).
    pub fn new(weights: &[f64]) -> Option<Self> {
        let total: f64 = weights.iter().sum();
        if !(total.is_finite() && total > 0.0) || weights.iter().any(|w| w.is_nan() || *w < 0.0) {
            return None;
        }
        let n = weights.len();
        let pmf: Vec<f64> = weights.iter().map(|w| w / total).collect();
        let mut bins: Vec<(f64, u32)> = (0..n as u32).map(|i| (1.0, i)).collect();
        let scaled: Vec<f64> = pmf.iter().map(|p| p * n as f64).collect();
        // (item, scaled probability) below 1 and at or above it.
        let mut small: Vec<(u32, f64)> = Vec::new();
        let mut large: Vec<(u32, f64)> = Vec::new();
        for (i, &s) in scaled.iter().enumerate() {
            match s < 1.0 {
                true => small.push((i as u32, s)),
                false => large.push((i as u32, s)),
            }
        }
        while let (Some((s, ps)), Some((l, pl))) = (small.pop(), large.pop()) {
            bins[s as usize] = (ps, l);
            let rest = pl + ps - 1.0;
            match rest < 1.0 {
                true => small.push((l, rest)),
                false => large.push((l, rest)),
            }
        }
        // What is left keeps its own item (rounding leaves probabilities near 1).
        for (i, _) in small.into_iter().chain(large) {
            bins[i as usize] = (1.0, i);
        }
        Some(Self { bins, pmf })
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// The probability of item `i`.
    pub fn pmf(&self, i: usize) -> f64 {
        self.pmf[i]
    }

    /// The item drawn by a uniform `u` in [0, 1), its probability, and `u` rescaled to
    /// [0, 1) within the choice (for reuse by what samples the item).
    pub fn sample(&self, u: f64) -> (usize, f64, f64) {
        let n = self.bins.len();
        let x = u * n as f64;
        let bin = (x as usize).min(n - 1);
        let up = (x - bin as f64).clamp(0.0, 1.0);
        let (keep, alias) = self.bins[bin];
        let (item, rescaled) = if up < keep {
            (bin, up / keep)
        } else {
            (alias as usize, ((up - keep) / (1.0 - keep)).clamp(0.0, 1.0))
        };
        (item, self.pmf[item], rescaled.min(1.0 - f64::EPSILON / 2.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table draws each item with its probability: a χ² over 200 000 draws of skewed
    /// weights, and a table whose claimed probabilities are those of other weights is
    /// rejected by the same statistic.
    #[test]
    fn draws_follow_the_weights_and_a_wrong_table_is_rejected() {
        let weights = [5.0, 0.0, 1.0, 0.25, 3.0, 10.0, 0.5];
        let table = AliasTable::new(&weights).unwrap();
        let n = 200_000;
        let mut counts = [0u64; 7];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..n {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let (i, p, r) = table.sample(u);
            assert_eq!(p, table.pmf(i));
            assert!((0.0..1.0).contains(&r));
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0, "an item of weight 0 was drawn");
        let statistic = |pmf: &dyn Fn(usize) -> f64| -> f64 {
            (0..7)
                .filter(|&i| pmf(i) > 0.0)
                .map(|i| {
                    let e = pmf(i) * n as f64;
                    (counts[i] as f64 - e).powi(2) / e
                })
                .sum()
        };
        // 5 degrees of freedom: the 99.9 % quantile is 20.5.
        let right = statistic(&|i| table.pmf(i));
        assert!(right < 20.5, "χ² {right}");
        let other = AliasTable::new(&[5.0, 0.0, 1.0, 0.25, 3.0, 10.5, 0.5]).unwrap();
        let wrong = statistic(&|i| other.pmf(i));
        assert!(wrong > 20.5, "a wrong table passed: χ² {wrong}");
    }

    #[test]
    fn no_weight_no_table() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, f64::NAN]).is_none());
        assert!(AliasTable::new(&[1.0, -1.0]).is_none());
        let one = AliasTable::new(&[2.0]).unwrap();
        assert_eq!(one.sample(0.999_999), (0, 1.0, 0.999_999));
    }
}
