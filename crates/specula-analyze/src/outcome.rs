//! The three-valued verdict every check, field and standard gives: `pass`, `fail`, or
//! `undecided` when the measurement cannot tell (its margin lies within its stated
//! uncertainty). Nothing passes on uncertainty: a check passes only when its margin is at least
//! its uncertainty, and fails only when its margin is below minus its uncertainty.
//!
//! A verdict over several checks is the worst of theirs: any `fail` fails it, else any
//! `undecided` leaves it undecided, else it passes.

use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    Pass,
    Fail,
    Undecided,
}

impl Outcome {
    /// The outcome of a check whose margin (positive: passing by that much, in the check's
    /// unit) is known to ± `uncertainty`. A margin of exactly zero with no uncertainty passes:
    /// the standards' limits include their edges.
    pub fn of_margin(margin: f64, uncertainty: f64) -> Outcome {
        let uncertainty = uncertainty.abs();
        // An unknown or unbounded uncertainty decides nothing.
        if margin.is_nan() || !uncertainty.is_finite() {
            Outcome::Undecided
        } else if margin >= uncertainty {
            Outcome::Pass
        } else if margin < -uncertainty {
            Outcome::Fail
        } else {
            Outcome::Undecided
        }
    }

    /// The worst of `outcomes` (a pass when there are none).
    pub fn all(outcomes: impl IntoIterator<Item = Outcome>) -> Outcome {
        outcomes.into_iter().fold(Outcome::Pass, Outcome::and)
    }

    /// The worse of two outcomes.
    pub fn and(self, other: Outcome) -> Outcome {
        match (self, other) {
            (Outcome::Fail, _) | (_, Outcome::Fail) => Outcome::Fail,
            (Outcome::Undecided, _) | (_, Outcome::Undecided) => Outcome::Undecided,
            _ => Outcome::Pass,
        }
    }

    pub fn passed(self) -> bool {
        self == Outcome::Pass
    }

    /// The word a report prints: PASS, FAIL or UNDECIDED.
    pub fn word(self) -> &'static str {
        match self {
            Outcome::Pass => "PASS",
            Outcome::Fail => "FAIL",
            Outcome::Undecided => "UNDECIDED",
        }
    }

    /// The lower-case word a table prints.
    pub fn lower(self) -> &'static str {
        match self {
            Outcome::Pass => "pass",
            Outcome::Fail => "fail",
            Outcome::Undecided => "undecided",
        }
    }
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.word())
    }
}

#[cfg(test)]
mod tests {
    use super::Outcome::{self, *};

    #[test]
    fn a_margin_within_its_uncertainty_is_undecided() {
        assert_eq!(Outcome::of_margin(0.3, 0.2), Pass);
        assert_eq!(Outcome::of_margin(0.1, 0.2), Undecided);
        assert_eq!(Outcome::of_margin(-0.1, 0.2), Undecided);
        assert_eq!(Outcome::of_margin(-0.3, 0.2), Fail);
        assert_eq!(Outcome::of_margin(0.0, 0.0), Pass);
        assert_eq!(Outcome::of_margin(-1e-12, 0.0), Fail);
        assert_eq!(Outcome::of_margin(f64::NAN, 0.0), Undecided);
        assert_eq!(Outcome::of_margin(f64::INFINITY, f64::INFINITY), Undecided);
        assert_eq!(Outcome::of_margin(-1.0, f64::NAN), Undecided);
        assert_eq!(Outcome::all([Pass, Undecided, Pass]), Undecided);
        assert_eq!(Outcome::all([Pass, Undecided, Fail]), Fail);
        assert_eq!(Outcome::all([]), Pass);
    }
}
