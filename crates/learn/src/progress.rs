//! The learning-curve CSV's columns (Python's `chopperscape.learn.progress.COLUMNS`) and one update's row,
//! formatted as Python's loop formats it.

/// The columns, in order.
pub const COLUMNS: [&str; 20] = [
    "env_steps",
    "wall_s",
    "episodes",
    "mean_return",
    "std_return",
    "mean_length",
    "learning_rate",
    "entropy",
    "approx_kl",
    "clip_frac",
    "explained_var",
    "value_loss",
    "policy_loss",
    "ended",
    "bird",
    "fuel",
    "limit",
    "aux_loss",
    "teacher_kl",
    "recon_loss",
];

/// What one update reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Decisions so far (reset steps not counted).
    pub env_steps: u64,
    /// Wall seconds of the run so far (as the caller measured them).
    pub wall_s: f64,
    /// Episodes finished so far.
    pub episodes: u64,
    /// Mean, population std and mean length of the last 100 finished episodes (`None` before the first).
    pub returns: Option<(f64, f64, f64)>,
    /// The update's learning rate.
    pub learning_rate: f64,
    /// Means over the update's minibatches.
    pub entropy: f64,
    /// Approximate KL.
    pub approx_kl: f64,
    /// Clip fraction.
    pub clip_frac: f64,
    /// Explained variance of the value targets (NaN when they do not vary).
    pub explained_var: f64,
    /// Value loss.
    pub value_loss: f64,
    /// Policy loss.
    pub policy_loss: f64,
    /// Episodes ended during the update by a bird, the fuel and the step limit.
    pub ends: [u64; 3],
}

/// Python's `f"{x:.6g}"`.
pub fn general(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return python_float(x, 0).replace(".", "");
    }
    let sci = format!("{x:.5e}");
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    if (-4..6).contains(&exp) {
        let fixed = format!("{:.*}", (5 - exp) as usize, x);
        trim(&fixed)
    } else {
        format!("{}e{}{:02}", trim(mantissa), if exp < 0 { '-' } else { '+' }, exp.abs())
    }
}

fn trim(s: &str) -> String {
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s.to_string() }
}

/// Python's `f"{x:.{digits}f}"` (`nan`, `inf` as Python spells them).
pub fn python_float(x: f64, digits: usize) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        format!("{x:.digits$}")
    }
}

impl Row {
    /// The row's fields in [`COLUMNS`]' order, as Python writes them (blank where it leaves them blank).
    pub fn fields(&self) -> Vec<String> {
        let f = python_float;
        let (mean, std, len) = match self.returns {
            Some((m, s, l)) => (f(m, 1), f(s, 1), f(l, 1)),
            None => (String::new(), String::new(), String::new()),
        };
        let ended: u64 = self.ends.iter().sum();
        let share = |k: usize| if ended > 0 { f(self.ends[k] as f64 / ended as f64, 3) } else { String::new() };
        vec![
            self.env_steps.to_string(),
            f(self.wall_s, 1),
            self.episodes.to_string(),
            mean,
            std,
            len,
            general(self.learning_rate),
            f(self.entropy, 4),
            f(self.approx_kl, 5),
            f(self.clip_frac, 4),
            f(self.explained_var, 4),
            f(self.value_loss, 5),
            f(self.policy_loss, 5),
            ended.to_string(),
            share(0),
            share(1),
            share(2),
            String::new(),
            String::new(),
            String::new(),
        ]
    }

    /// The CSV line (no newline); no field needs quoting.
    pub fn csv_line(&self) -> String {
        self.fields().join(",")
    }
}

/// The CSV header line (no newline).
pub fn header() -> String {
    COLUMNS.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_as_python_writes_them() {
        assert_eq!(general(0.001), "0.001");
        assert_eq!(general(5e-5), "5e-05");
        assert_eq!(general(0.000_966_4), "0.0009664");
        assert_eq!(general(0.000_123_456_789), "0.000123457");
        assert_eq!(general(3e-4), "0.0003");
        assert_eq!(python_float(f64::NAN, 4), "nan");
        assert_eq!(python_float(0.125, 1), "0.1");
    }
}
