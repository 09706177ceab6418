//! Summary statistics of repeated measurements (the bench's and the viewer's offscreen report), and the fits
//! the bench's error curves need.

/// Median and spread (minimum, 10th / 90th / 99th percentile) of a set of measurements. The minimum is the
/// robust figure on a shared CPU, where other processes only ever add time.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub p10: f64,
    pub p90: f64,
    pub p99: f64,
}

impl Spread {
    /// NaNs (a measurement that did not happen) are left out; all-NaN input gives NaN everywhere.
    pub fn of(values: &[f64]) -> Self {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
        if v.is_empty() {
            return Self {
                min: f64::NAN,
                median: f64::NAN,
                p10: f64::NAN,
                p90: f64::NAN,
                p99: f64::NAN,
            };
        }
        v.sort_by(f64::total_cmp);
        Self {
            min: v[0],
            median: percentile(&v, 0.5),
            p10: percentile(&v, 0.1),
            p90: percentile(&v, 0.9),
            p99: percentile(&v, 0.99),
        }
    }
}

/// Nearest-rank percentile of sorted values, `p` in 0..=1.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// Least-squares slope and intercept of ln(y) against ln(x); points with a non-positive coordinate are skipped.
pub fn log_log_fit(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let cov: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let var: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    (var > 0.0).then(|| {
        let slope = cov / var;
        (slope, my - slope * mx)
    })
}

/// When a decreasing error curve `(time, error)` first reaches `target`: interpolated in log-log space
/// between the two measurements around the crossing. `None` if it never gets there.
pub fn time_to_reach(curve: &[(f64, f64)], target: f64) -> Option<f64> {
    let first = curve.first()?;
    if first.1 <= target {
        return Some(first.0);
    }
    curve.windows(2).find_map(|w| {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        if e1 > target || e0 <= 0.0 || e1 <= 0.0 || t0 <= 0.0 {
            return None;
        }
        let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
        Some((t0.ln() + f * (t1.ln() - t0.ln())).exp())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_of_known_values() {
        let v: Vec<f64> = (1..=101).map(f64::from).collect();
        let s = Spread::of(&v);
        assert_eq!(
            (s.min, s.median, s.p10, s.p90, s.p99),
            (1.0, 51.0, 11.0, 91.0, 100.0)
        );
        assert!(Spread::of(&[f64::NAN]).median.is_nan());
    }

    #[test]
    fn log_log_fit_recovers_a_power_law() {
        let pts: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0, 16.0]
            .iter()
            .map(|&x: &f64| (x, 3.0 * x.powf(-0.5)))
            .collect();
        let (slope, intercept) = log_log_fit(&pts).unwrap();
        assert!((slope + 0.5).abs() < 1e-12);
        assert!((intercept - 3f64.ln()).abs() < 1e-12);
    }

    #[test]
    fn time_to_reach_interpolates_in_log_space() {
        // error = 1 / t: reaches 0.1 at t = 10, between the measurements at 4 and 16.
        let curve = [(1.0, 1.0), (4.0, 0.25), (16.0, 0.0625)];
        assert!((time_to_reach(&curve, 0.1).unwrap() - 10.0).abs() < 1e-9);
        assert_eq!(time_to_reach(&curve, 0.01), None);
        assert_eq!(time_to_reach(&curve, 2.0), Some(1.0));
    }
}
