//! Which of every pixel's samples a render takes.

/// Which of every pixel's samples a render takes: sample `s` belongs to shard `s mod count`
/// (docs/shards.md), so the shards of one render share no random stream, together are that
/// render, and any subset of them is an unbiased render with fewer samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// `K` of `K/N`: `0 ≤ index < count`.
    pub index: u32,
    /// `N` of `K/N`.
    pub count: u32,
}

impl Shard {
    /// Every sample: the render on one machine.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    pub fn is_whole(&self) -> bool {
        self.count == 1
    }

    /// The indices of this shard's samples among a pixel's `spp`.
    pub fn samples(&self, spp: u32) -> std::iter::StepBy<std::ops::Range<u32>> {
        (self.index.min(spp)..spp).step_by(self.count as usize)
    }

    /// How many of a pixel's `spp` samples are this shard's.
    pub fn samples_of(&self, spp: u32) -> u32 {
        spp.saturating_sub(self.index).div_ceil(self.count)
    }
}

impl Default for Shard {
    fn default() -> Self {
        Self::WHOLE
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Why a text is not a shard `K/N`; each names the text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ShardParseError {
    #[error("`{0}` is not K/N (shard K of N, 0 ≤ K < N, e.g. 0/4)")]
    NotKOfN(String),
    #[error("`{0}`: the number of shards N must be at least 1")]
    NoShards(String),
    #[error("`{0}`: at most {MAX_SHARDS} shards")]
    TooMany(String),
    #[error("`{0}`: shard K must be below N (shards are numbered 0 to N − 1)")]
    IndexNotBelowCount(String),
}

impl std::str::FromStr for Shard {
    type Err = ShardParseError;

    /// `K/N` with `0 ≤ K < N`.
    fn from_str(text: &str) -> Result<Self, ShardParseError> {
        let not = || ShardParseError::NotKOfN(text.to_string());
        let (k, n) = text.split_once('/').ok_or_else(not)?;
        let index: u32 = k.trim().parse().map_err(|_| not())?;
        let count: u32 = n.trim().parse().map_err(|_| not())?;
        if count == 0 {
            return Err(ShardParseError::NoShards(text.to_string()));
        }
        if count > MAX_SHARDS {
            return Err(ShardParseError::TooMany(text.to_string()));
        }
        if index >= count {
            return Err(ShardParseError::IndexNotBelowCount(text.to_string()));
        }
        Ok(Self { index, count })
    }
}

/// The most shards a render can be split into (the most samples per pixel).
pub const MAX_SHARDS: u32 = 1 << 24;
