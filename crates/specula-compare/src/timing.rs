//! Frame times as `compare` and `bench` report them: N warm frames (each method prepared and its
//! first frame, which pays for shader compilation and first use, rendered and timed apart), as
//! their median and spread, so that every ratio divides a warm median by a warm median.

use serde::Serialize;

/// The median and the extremes of a set of times, in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

impl Spread {
    /// Of `values` (at least one).
    pub fn of(mut values: Vec<f64>) -> Spread {
        assert!(!values.is_empty(), "a spread of no times");
        values.sort_by(f64::total_cmp);
        let n = values.len();
        let median = if n % 2 == 1 {
            values[n / 2]
        } else {
            0.5 * (values[n / 2 - 1] + values[n / 2])
        };
        Spread {
            median_ms: median,
            min_ms: values[0],
            max_ms: values[n - 1],
        }
    }
}

/// `base_ms` over `ms`: how many times faster a run of `ms` is than one of `base_ms`.
pub fn speedup(base_ms: f64, ms: f64) -> f64 {
    base_ms / ms.max(1e-9)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spread_is_the_median_and_the_extremes() {
        let odd = Spread::of(vec![5.0, 1.0, 9.0]);
        assert_eq!((odd.min_ms, odd.median_ms, odd.max_ms), (1.0, 5.0, 9.0));
        let even = Spread::of(vec![10.0, 3.0, 1.0, 2.0]);
        assert_eq!((even.min_ms, even.median_ms, even.max_ms), (1.0, 2.5, 10.0));
    }
}
