//! The values of a swept field, as given on the command line (`--values`, `--range`,
//! `--log-range`), and how a number is written into a scene.

use serde::Serialize;

use crate::output::csv::push_f64;

/// Most values a sweep may have.
pub const MAX_VALUES: usize = 10_000;

/// One value of the swept field: the text given to the scene and its number.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepValue {
    pub text: String,
    pub x: f64,
}

/// How the values were given on the command line.
#[derive(Clone, Copy, Debug)]
pub enum ValueSpec<'a> {
    /// `--values a,b,c`.
    List(&'a str),
    /// `--range lo:hi:count`, evenly spaced.
    Range(&'a str),
    /// `--log-range lo:hi:count`, evenly spaced in `log`.
    LogRange(&'a str),
}

/// A number as a scene value: a whole number without a fraction (so that integer fields
/// such as `junctions.n` accept it), anything else in the shortest round-trip form.
pub fn value_text(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        let mut s = String::new();
        push_f64(&mut s, x);
        s
    }
}

/// `x` rounded to 6 significant digits (the inner points of a range, so that the values
/// read well; the end points are kept exactly as given).
pub fn round_sig(x: f64) -> f64 {
    format!("{x:.5e}").parse().expect("a formatted float parses")
}

/// Why a list of values was refused: one line naming the argument, the text and what is
/// allowed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ValuesError {
    #[error("--values {list}: '{item}' is not a finite number (expected numbers separated by commas, e.g. 0.1,0.5,2)")]
    NotANumber { list: String, item: String },
    #[error("--values: {count} values given, at most {MAX_VALUES} allowed")]
    TooMany { count: usize },
    #[error("{flag} {text}: {problem} ({})", range_form(.flag))]
    BadRange { flag: &'static str, text: String, problem: RangeProblem },
}

/// What is wrong with a `LO:HI:COUNT` range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RangeProblem {
    #[error("not three fields separated by ':'")]
    NotThreeFields,
    #[error("{name} '{text}' is not a finite number")]
    NotFinite { name: &'static str, text: String },
    #[error("COUNT '{text}' is not a whole number from 2 to {MAX_VALUES}")]
    BadCount { text: String },
    #[error("LO = {lo} is not > 0")]
    LoNotPositive { lo: f64 },
    #[error("LO = {lo} is not less than HI = {hi}")]
    LoNotBelowHi { lo: f64, hi: f64 },
}

fn range_form(flag: &str) -> &'static str {
    if flag == "--log-range" {
        "expected LO:HI:COUNT with 0 < LO < HI and COUNT from 2 to 10000, e.g. 0.1:10:9"
    } else {
        "expected LO:HI:COUNT with LO < HI and COUNT from 2 to 10000, e.g. 0:2:5"
    }
}

impl ValueSpec<'_> {
    /// The command-line flag the values were given with.
    pub fn flag(&self) -> &'static str {
        match self {
            ValueSpec::List(_) => "--values",
            ValueSpec::Range(_) => "--range",
            ValueSpec::LogRange(_) => "--log-range",
        }
    }
}

/// Parses the values.
pub fn parse_values(spec: ValueSpec<'_>) -> Result<Vec<SweepValue>, ValuesError> {
    let printable = crate::scene::error::printable;
    match spec {
        ValueSpec::List(s) => {
            let mut out = Vec::new();
            for part in s.split(',') {
                let text = part.trim();
                let x = text
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| ValuesError::NotANumber { list: printable(s), item: printable(text) })?;
                out.push(SweepValue { text: text.to_string(), x });
            }
            if out.len() > MAX_VALUES {
                return Err(ValuesError::TooMany { count: out.len() });
            }
            Ok(out)
        }
        ValueSpec::Range(s) | ValueSpec::LogRange(s) => {
            let log = matches!(spec, ValueSpec::LogRange(_));
            let bad = |problem: RangeProblem| ValuesError::BadRange { flag: spec.flag(), text: printable(s), problem };
            let parts: Vec<&str> = s.split(':').map(str::trim).collect();
            if parts.len() != 3 {
                return Err(bad(RangeProblem::NotThreeFields));
            }
            let num = |t: &str, name: &'static str| {
                t.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(RangeProblem::NotFinite { name, text: printable(t) }))
            };
            let (lo, hi) = (num(parts[0], "LO")?, num(parts[1], "HI")?);
            let count: usize = parts[2]
                .parse()
                .ok()
                .filter(|c| (2..=MAX_VALUES).contains(c))
                .ok_or_else(|| bad(RangeProblem::BadCount { text: printable(parts[2]) }))?;
            if log && lo <= 0.0 {
                return Err(bad(RangeProblem::LoNotPositive { lo }));
            }
            if lo >= hi {
                return Err(bad(RangeProblem::LoNotBelowHi { lo, hi }));
            }
            let xs: Vec<f64> = (0..count)
                .map(|k| {
                    let f = k as f64 / (count - 1) as f64;
                    match k {
                        0 => lo,
                        k if k == count - 1 => hi,
                        _ if log => round_sig((lo.ln() + f * (hi.ln() - lo.ln())).exp()),
                        _ => round_sig(lo + f * (hi - lo)),
                    }
                })
                .collect();
            Ok(xs.into_iter().map(|x| SweepValue { text: value_text(x), x }).collect())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_hit_their_ends() {
        let v = parse_values(ValueSpec::LogRange("0.1:10:3")).unwrap();
        assert_eq!(v.iter().map(|v| v.x).collect::<Vec<_>>(), vec![0.1, 1.0, 10.0]);
        assert_eq!(v[2].text, "10");
        let v = parse_values(ValueSpec::Range("0:2:5")).unwrap();
        assert_eq!(v.iter().map(|v| v.text.as_str()).collect::<Vec<_>>(), vec!["0", "0.5", "1", "1.5", "2"]);
        let v = parse_values(ValueSpec::List("0.1, 1e-3,300")).unwrap();
        assert_eq!(v.iter().map(|v| v.text.as_str()).collect::<Vec<_>>(), vec!["0.1", "1e-3", "300"]);
    }

    #[test]
    fn bad_values_are_refused_with_the_argument_named() {
        for (spec, arg) in [
            (ValueSpec::List("0.1,,2"), "--values"),
            (ValueSpec::List("0.1,abc"), "--values"),
            (ValueSpec::List("nan"), "--values"),
            (ValueSpec::LogRange("0:1:5"), "--log-range"),
            (ValueSpec::LogRange("1:0.1:5"), "--log-range"),
            (ValueSpec::LogRange("0.1:1:1"), "--log-range"),
            (ValueSpec::LogRange("0.1:1"), "--log-range"),
            (ValueSpec::Range("1:2:x"), "--range"),
        ] {
            let e = parse_values(spec).unwrap_err().to_string();
            assert!(e.starts_with(arg), "{e}");
            assert!(!e.contains('\n'));
        }
    }
}
