//! Requirement kinds, one file per kind: what a design must meet at a speed, read from the
//! model file (`[[requirements]]`), as a margin that is positive where it is met.
//!
//! Each kind owns its name, the fields it takes, what it reads of a design at a speed (a mode's
//! ω_d and ζ, the largest growth rate of any root, |H|, or whether the design is on the nominal
//! branch), the unit of its margin, the margin itself written once over any [`Real`] (so that
//! the first-order yield differentiates it exactly), and its sentence in the report. Where the
//! margins are read from a design is [`crate::margins`]; the rest of the program asks the kind.
//!
//! Adding a kind is one file here implementing [`RequirementType`] and one line in the list
//! below; the model parser reads the kind's name and fields from that trait, and needs a change
//! only where the kind brings a field no kind had ([`Fields`]).

pub mod avoid;
pub mod branch;
pub mod damping;
pub mod frequency;
pub mod separation;
pub mod stable;
pub mod transfer;
pub mod underdamped;

use crate::kinds::kinds;
use crate::real::Real;
use std::ops::Range;
use toml::Spanned;

/// What a kind reads of a design at one speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reads {
    /// A mode's ω_d and ζ: the requirement is per mode (`mode = k`, or the worst mode).
    Mode,
    /// The largest growth rate of any root.
    Growth,
    /// The transfer function's magnitude |H| (needs `[analysis] transfer`).
    Transfer,
    /// Whether the design is on the nominal design's equilibrium branch: pass or fail, no
    /// margin with a distribution.
    Branch,
}

/// What a requirement reads of a design at one speed, over a scalar `S` (see [`Reads`]).
#[derive(Debug, Clone, Copy)]
pub enum Reading<S> {
    /// A mode's damped frequency (rad/s) and damping ratio; `real_pair` where `p = λ₁λ₂ ≤ 0`,
    /// so that the roots are real whatever `s = λ₁ + λ₂` and ζ says nothing of them.
    Mode { wd: S, zeta: S, real_pair: bool },
    /// The largest real part of any root, less a relative tolerance (1/s).
    Growth(S),
    /// |H|, in the transfer function's unit (NaN where it has no value).
    Transfer(S),
    /// On the nominal design's branch?
    Branch(bool),
}

/// The unit of a kind's margin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarginUnit {
    RadPerSecond,
    One,
    PerSecond,
    /// The transfer function's unit (the model's `[analysis] transfer`).
    Transfer,
    /// No margin (pass or fail).
    None,
}

impl MarginUnit {
    /// The symbol, with `transfer` naming |H|'s unit.
    pub fn symbol(self, transfer: &str) -> String {
        match self {
            MarginUnit::RadPerSecond => "rad/s".into(),
            MarginUnit::One => "1".into(),
            MarginUnit::PerSecond => "1/s".into(),
            MarginUnit::Transfer => transfer.into(),
            MarginUnit::None => String::new(),
        }
    }
}

/// The fields of a `[[requirements]]` entry a kind may take, with where they were written.
#[derive(Debug, Clone, Copy)]
pub struct Fields<'a> {
    /// How the requirement is named in messages (`requirement 'r1'`).
    pub what: &'a str,
    /// Where its `kind` is written (a missing field is reported there).
    pub kind: &'a Spanned<String>,
    pub orders: Option<&'a Spanned<Vec<f64>>>,
    pub margin: Option<&'a Spanned<String>>,
    pub band: Option<&'a Spanned<Vec<f64>>>,
    pub min: Option<&'a Spanned<f64>>,
    pub max: Option<&'a Spanned<f64>>,
}

/// A field that does not say what its kind needs: where, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    pub span: Range<usize>,
    pub message: String,
}

impl<'a> Fields<'a> {
    /// The names of the fields given, with where they are, in the order the format lists them.
    pub fn given(&self) -> [(&'static str, Option<Range<usize>>); 5] {
        [
            ("orders", self.orders.map(|x| x.span())),
            ("margin", self.margin.map(|x| x.span())),
            ("band", self.band.map(|x| x.span())),
            ("min", self.min.map(|x| x.span())),
            ("max", self.max.map(|x| x.span())),
        ]
    }

    /// The field, or the error that the kind needs it.
    pub fn need<T>(
        &self,
        field: Option<&'a Spanned<T>>,
        name: &str,
    ) -> Result<&'a Spanned<T>, Invalid> {
        field.ok_or_else(|| self.missing(name))
    }

    /// The error that the kind needs `name`.
    pub fn missing(&self, name: &str) -> Invalid {
        self.invalid(
            self.kind.span(),
            format!("a '{}' requirement needs '{name}'", self.kind.get_ref()),
        )
    }

    /// A number that must be finite (and `> 0` where `positive`).
    pub fn finite(&self, v: &Spanned<f64>, name: &str, positive: bool) -> Result<f64, Invalid> {
        let x = *v.get_ref();
        if !x.is_finite() || (positive && x <= 0.0) {
            let need = if positive { "finite and > 0" } else { "finite" };
            return Err(self.invalid(v.span(), format!("{name} must be {need}")));
        }
        Ok(x)
    }

    /// An error at `span`, prefixed with the requirement's name.
    pub fn invalid(&self, span: Range<usize>, message: String) -> Invalid {
        Invalid {
            span,
            message: format!("{}: {message}", self.what),
        }
    }
}

/// A requirement kind: its settings are the type's value.
pub trait RequirementType: Sized {
    /// Name in the model file's `kind` field (and the outputs' `kind` column).
    const NAME: &'static str;
    /// The fields it takes besides `name`, `kind`, `speeds` and `mode`.
    const FIELDS: &'static [&'static str];
    /// What it reads of a design at a speed.
    const READS: Reads;
    /// The unit of its margin.
    const UNIT: MarginUnit;
    /// Its settings from the fields written (each of [`RequirementType::FIELDS`] or absent).
    fn read(fields: &Fields) -> Result<Self, Invalid>;
    /// Its margin at `speed` (rad/s) from what it reads (≥ 0: met; NaN where the reading is not
    /// of its kind or the quantity has no value).
    fn margin<S: Real>(&self, speed: f64, at: Reading<S>) -> S;
    /// The requirement in words, `mode` naming the mode(s) it reads (`mode 2`, `every mode`).
    fn describe(&self, mode: &str) -> String;
    /// The tightest requirement of this kind met with the worst margin `q` (finite, in the
    /// margin's unit), in words: each bound moved by `q`; `transfer` names |H|'s unit.
    fn tightest(&self, mode: &str, q: f64, transfer: &str) -> String;
}

kinds! {
    /// The requirement kinds a model may use, with their settings.
    pub enum Kind: RequirementType {
        Separation(separation::Separation),
        Frequency(frequency::Frequency),
        Avoid(avoid::Avoid),
        Damping(damping::Damping),
        Underdamped(underdamped::Underdamped),
        Stable(stable::Stable),
        SameBranch(branch::SameBranch),
        Transfer(transfer::Transfer),
    }
    read(&Fields) -> Invalid;
    /// What it reads of a design.
    fn reads() -> Reads = READS;
    /// The unit of its margin.
    fn unit() -> MarginUnit = UNIT;
    /// See [`RequirementType::margin`].
    fn margin<S: Real>(speed: f64, at: Reading<S>) -> S = margin(speed, at);
    /// See [`RequirementType::describe`].
    fn describe(mode: &str) -> String = describe(mode);
    /// See [`RequirementType::tightest`].
    fn tightest(mode: &str, q: f64, transfer: &str) -> String = tightest(mode, q, transfer);
}

/// The side of a band a value is on: the larger of the margins below and above it.
fn outside<S: Real>(under: S, over: S) -> S {
    if under.re() >= over.re() { under } else { over }
}

/// A number in a tightest requirement (six decimals).
fn g(x: f64) -> String {
    format!("{x:.6}")
}
