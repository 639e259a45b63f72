//! Medians and spreads: every timing quadray reports is the median of many runs.

use serde::Serialize;

/// Median and spread of a series of timings (milliseconds).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Summary {
    pub median_ms: f64,
    pub p10_ms: f64,
    pub p90_ms: f64,
    pub samples: usize,
}

impl Summary {
    /// Sorts `samples` in place; `None` when there are none.
    pub fn from_samples(samples: &mut [f64]) -> Option<Self> {
        if samples.is_empty() {
            return None;
        }
        samples.sort_by(f64::total_cmp);
        let at = |q: f64| samples[((samples.len() - 1) as f64 * q).round() as usize];
        Some(Self {
            median_ms: at(0.5),
            p10_ms: at(0.1),
            p90_ms: at(0.9),
            samples: samples.len(),
        })
    }
}

/// Times `f` on the CPU `runs` times (after one warm-up run) and summarises the wall times.
pub fn time_cpu<T>(runs: usize, mut f: impl FnMut() -> T) -> (T, Summary) {
    let mut out = f();
    let mut samples: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            let start = std::time::Instant::now();
            out = f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    (
        out,
        Summary::from_samples(&mut samples).expect("at least one run"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_percentiles_of_an_odd_series() {
        let mut s = [5.0, 1.0, 4.0, 2.0, 3.0];
        let sum = Summary::from_samples(&mut s).unwrap();
        assert_eq!(sum.median_ms, 3.0);
        assert_eq!(sum.p10_ms, 1.0);
        assert_eq!(sum.p90_ms, 5.0);
        assert_eq!(sum.samples, 5);
        assert!(Summary::from_samples(&mut []).is_none());
    }
}
