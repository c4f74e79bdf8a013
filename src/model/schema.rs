//! Serde structures that mirror the TOML model file one to one, with source spans.
//!
//! Nothing here is checked beyond TOML types; `validate` turns these into a
//! [`super::Model`]. Spans are byte ranges into the file, turned into line and column there.

use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

/// A numeric field: a number, or an expression string over the parameters.
#[derive(Debug, Clone)]
pub enum Num {
    Value(f64),
    Expr(String),
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Num;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an expression string such as \"m*L^2/12\"")
            }
            fn visit_i64<E>(self, v: i64) -> Result<Num, E> {
                Ok(Num::Value(v as f64))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Num, E> {
                Ok(Num::Value(v as f64))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Num, E> {
                Ok(Num::Value(v))
            }
            fn visit_str<E>(self, v: &str) -> Result<Num, E> {
                Ok(Num::Expr(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// A spanned number-or-expression.
pub type SNum = Spanned<Num>;

/// A number or expression, or a list of them: one value per coordinate of a joint (a single
/// value serves a one-coordinate joint, and for spring rates and damping every coordinate);
/// or a list of lists, a matrix by rows (a force element's stiffness and damping).
#[derive(Debug, Clone)]
pub enum Nums {
    One(Num),
    Many(Vec<SNum>),
    Rows(Vec<Spanned<Vec<SNum>>>),
}

/// An entry of a [`Nums`] list: a value, or a row of a matrix.
enum Entry {
    Value(Num),
    Row(Vec<SNum>),
}

impl<'de> Deserialize<'de> for Entry {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Entry;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, an expression string, or a list of them (a matrix's row)")
            }
            fn visit_i64<E>(self, v: i64) -> Result<Entry, E> {
                Ok(Entry::Value(Num::Value(v as f64)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Entry, E> {
                Ok(Entry::Value(Num::Value(v as f64)))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Entry, E> {
                Ok(Entry::Value(Num::Value(v)))
            }
            fn visit_str<E>(self, v: &str) -> Result<Entry, E> {
                Ok(Entry::Value(Num::Expr(v.to_string())))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Entry, A::Error> {
                let mut out = Vec::new();
                while let Some(x) = seq.next_element::<SNum>()? {
                    out.push(x);
                }
                Ok(Entry::Row(out))
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for Nums {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Nums;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, an expression string, or a list of them")
            }
            fn visit_i64<E>(self, v: i64) -> Result<Nums, E> {
                Ok(Nums::One(Num::Value(v as f64)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Nums, E> {
                Ok(Nums::One(Num::Value(v as f64)))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Nums, E> {
                Ok(Nums::One(Num::Value(v)))
            }
            fn visit_str<E>(self, v: &str) -> Result<Nums, E> {
                Ok(Nums::One(Num::Expr(v.to_string())))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Nums, A::Error> {
                let (mut values, mut rows) = (Vec::new(), Vec::new());
                while let Some(x) = seq.next_element::<Spanned<Entry>>()? {
                    let span = x.span();
                    match x.into_inner() {
                        Entry::Value(v) => values.push(Spanned::new(span, v)),
                        Entry::Row(r) => rows.push(Spanned::new(span, r)),
                    }
                }
                match (values.is_empty(), rows.is_empty()) {
                    (_, true) => Ok(Nums::Many(values)),
                    (true, false) => Ok(Nums::Rows(rows)),
                    (false, false) => Err(serde::de::Error::custom(
                        "a list of values or a matrix (a list of rows), not a mix of the two",
                    )),
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// A spanned [`Nums`].
pub type SNums = Spanned<Nums>;
/// A spanned list of numbers (a vector, checked to have three entries later).
pub type SVec = Spanned<Vec<SNum>>;

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FileSchema {
    pub name: Option<Spanned<String>>,
    pub description: Option<Spanned<String>>,
    pub gravity: Option<SVec>,
    pub independent: Option<Spanned<Vec<Spanned<String>>>>,
    #[serde(default)]
    pub parameters: BTreeMap<Spanned<String>, Spanned<toml::Value>>,
    #[serde(default)]
    pub bodies: Vec<Spanned<BodySchema>>,
    #[serde(default)]
    pub joints: Vec<Spanned<JointSchema>>,
    #[serde(default)]
    pub forces: Vec<Spanned<ForceSchema>>,
    #[serde(default)]
    pub beams: Vec<Spanned<BeamSchema>>,
    #[serde(default)]
    pub shafts: Vec<Spanned<ShaftSchema>>,
    #[serde(default)]
    pub tables: Vec<Spanned<TableSchema>>,
    #[serde(default)]
    pub constraints: Vec<Spanned<ConstraintSchema>>,
    #[serde(default)]
    pub ports: Vec<Spanned<PortSchema>>,
    #[serde(default)]
    pub loads: Vec<Spanned<LoadSchema>>,
    #[serde(default)]
    pub unbalances: Vec<Spanned<UnbalanceSchema>>,
    #[serde(default)]
    pub couplers: Vec<Spanned<CouplerSchema>>,
    pub analysis: Option<Spanned<AnalysisSchema>>,
    #[serde(default)]
    pub requirements: Vec<Spanned<RequirementSchema>>,
    pub allocation: Option<Spanned<AllocationSchema>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySchema {
    pub name: Spanned<String>,
    pub mass: SNum,
    /// Principal values `[Ixx, Iyy, Izz]` or a full symmetric 3×3 matrix (numbers or
    /// expressions); interpreted in `validate`.
    pub inertia: Option<Spanned<toml::Value>>,
    /// The axes `inertia` is given in (default: the global axes as drawn).
    pub x_axis: Option<SVec>,
    pub y_axis: Option<SVec>,
    pub cm: SVec,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSchema {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub parent: Spanned<String>,
    pub child: Spanned<String>,
    pub at: Option<SVec>,
    pub axis: Option<SVec>,
    pub axis2: Option<SVec>,
    pub initial: Option<SNums>,
    pub drive: Option<SNum>,
    pub stiffness: Option<SNums>,
    pub free: Option<SNums>,
    pub damping: Option<SNums>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSchema {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub body1: Spanned<String>,
    pub point1: Option<SVec>,
    pub body2: Spanned<String>,
    pub point2: Option<SVec>,
    pub axis: Option<SVec>,
    pub axis2: Option<SVec>,
    pub stiffness: Option<SNums>,
    pub damping: Option<SNums>,
    #[serde(alias = "free_length")]
    pub free: Option<SNums>,
    pub preload: Option<SNums>,
}

/// One `[[tables]]` entry: a function of one argument tabulated at increasing `x`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSchema {
    pub name: Spanned<String>,
    pub x: Spanned<Vec<f64>>,
    pub y: Spanned<Vec<f64>>,
}

/// One `[[beams]]` entry: a Timoshenko beam element between two bodies, its section given by
/// a circular tube's geometry and material or by its section properties.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamSchema {
    pub name: Spanned<String>,
    pub body1: Spanned<String>,
    pub point1: SVec,
    pub body2: Spanned<String>,
    pub point2: SVec,
    /// The direction the section's second axis `e₂` is taken from.
    pub reference: Option<SVec>,
    pub outer_diameter: Option<SNum>,
    pub inner_diameter: Option<SNum>,
    #[serde(rename = "E")]
    pub youngs: Option<SNum>,
    #[serde(rename = "G")]
    pub shear_modulus: Option<SNum>,
    pub nu: Option<SNum>,
    pub density: Option<SNum>,
    pub shear_coefficient: Option<SNum>,
    #[serde(rename = "EA")]
    pub ea: Option<SNum>,
    #[serde(rename = "GJ")]
    pub gj: Option<SNum>,
    #[serde(rename = "EI")]
    pub ei: Option<SNums>,
    #[serde(rename = "kGA")]
    pub kga: Option<SNums>,
    #[serde(rename = "rhoA")]
    pub rho_a: Option<SNum>,
    #[serde(rename = "rhoI")]
    pub rho_i: Option<SNums>,
    /// Stiffness-proportional material damping: each deformation's force is
    /// `k (e + β ė)`, s.
    pub beta: Option<SNum>,
}

/// One `[[shafts]]` entry: a straight line of beam elements meshed from stations, its nodes
/// generated as bodies on joints (`validate::shafts` writes them out as the other tables).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShaftSchema {
    pub name: Spanned<String>,
    /// The first node's point, m.
    pub start: SVec,
    /// The direction the stations follow from `start` (any length).
    pub axis: SVec,
    pub reference: Option<SVec>,
    /// The body the nodes' joints hang from (default `ground`).
    pub parent: Option<Spanned<String>>,
    /// A body that is the first (last) node instead of a generated one: a hub, a clamp.
    pub start_body: Option<Spanned<String>>,
    pub end_body: Option<Spanned<String>>,
    /// The rate at which the nodes spin about the axis (a drive, usually `"speed"`).
    pub spin: Option<SNum>,
    /// Torsional stiffness from the parent to the first node's frame about the axis, N·m/rad.
    pub coupling: Option<SNum>,
    /// Material shared by the stations (each station may give its own).
    #[serde(rename = "E")]
    pub youngs: Option<SNum>,
    #[serde(rename = "G")]
    pub shear_modulus: Option<SNum>,
    pub nu: Option<SNum>,
    pub density: Option<SNum>,
    pub shear_coefficient: Option<SNum>,
    pub beta: Option<SNum>,
    pub stations: Spanned<Vec<Spanned<StationSchema>>>,
}

/// One station of a shaft: a length of uniform (or linearly tapered) section, meshed into
/// `elements` equal beam elements. The section keys are those of `[[beams]]`; a diameter may
/// be a pair `[start, end]` for a taper.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StationSchema {
    pub length: SNum,
    pub elements: Option<Spanned<i64>>,
    pub outer_diameter: Option<SNums>,
    pub inner_diameter: Option<SNums>,
    #[serde(rename = "E")]
    pub youngs: Option<SNum>,
    #[serde(rename = "G")]
    pub shear_modulus: Option<SNum>,
    pub nu: Option<SNum>,
    pub density: Option<SNum>,
    pub shear_coefficient: Option<SNum>,
    #[serde(rename = "EA")]
    pub ea: Option<SNum>,
    #[serde(rename = "GJ")]
    pub gj: Option<SNum>,
    #[serde(rename = "EI")]
    pub ei: Option<SNums>,
    #[serde(rename = "kGA")]
    pub kga: Option<SNums>,
    #[serde(rename = "rhoA")]
    pub rho_a: Option<SNum>,
    #[serde(rename = "rhoI")]
    pub rho_i: Option<SNums>,
    pub beta: Option<SNum>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSchema {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub body1: Spanned<String>,
    pub point1: SVec,
    pub body2: Spanned<String>,
    pub point2: Option<SVec>,
    pub axis: Option<SVec>,
    pub axis2: Option<SVec>,
    pub length: Option<SNum>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransferSchema {
    pub input: Spanned<String>,
    pub output: Spanned<String>,
    pub order: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PortSchema {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub body: Spanned<String>,
    pub point: Option<SVec>,
    pub direction: SVec,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnbalanceSchema {
    pub name: Spanned<String>,
    pub body: Spanned<String>,
    pub point: Option<SVec>,
    pub magnitude: SNum,
    pub phase: Option<SNum>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplerSchema {
    pub name: Spanned<String>,
    pub coordinates: Spanned<Vec<Spanned<String>>>,
    pub coefficients: SVec,
    pub value: Option<SNum>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSchema {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub body: Option<Spanned<String>>,
    pub point: Option<SVec>,
    pub force: Option<SVec>,
    pub torque: Option<SVec>,
    pub frame: Option<Spanned<String>>,
    pub coordinate: Option<Spanned<String>>,
    pub value: Option<SNum>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseSchema {
    pub name: Spanned<String>,
    pub tolerances: BTreeMap<Spanned<String>, Spanned<toml::Value>>,
    /// Correlation matrix, rows and columns in the order the tolerances are written.
    pub correlation: Option<Spanned<Vec<Vec<f64>>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisSchema {
    pub speed: Option<Spanned<String>>,
    pub transfer: Option<Spanned<TransferSchema>>,
    pub samples: Option<Spanned<i64>>,
    pub seed: Option<u64>,
    pub sampling: Option<Spanned<String>>,
    #[serde(default)]
    pub cases: Vec<Spanned<CaseSchema>>,
}

/// One `[[requirements]]` entry: what a design must meet over an operating range.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RequirementSchema {
    pub name: Option<Spanned<String>>,
    pub kind: Spanned<String>,
    /// Operating range `[from, to]`, rad/s.
    pub speeds: Option<Spanned<Vec<f64>>>,
    /// 1-based mode.
    pub mode: Option<Spanned<i64>>,
    /// Engine orders (separation).
    pub orders: Option<Spanned<Vec<f64>>>,
    /// `"P%"` or `"api684"` (separation).
    pub margin: Option<Spanned<String>>,
    /// Frequency band `[low, high]`, rad/s (avoid).
    pub band: Option<Spanned<Vec<f64>>>,
    pub min: Option<Spanned<f64>>,
    pub max: Option<Spanned<f64>>,
}

/// The `[allocation]` table: the yield target and the cost model of tolerance allocation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AllocationSchema {
    pub target_yield: Option<Spanned<f64>>,
    /// The tolerance case whose variables are allocated (default: the parameters' own).
    pub case: Option<Spanned<String>>,
    #[serde(default)]
    pub cost: BTreeMap<Spanned<String>, Spanned<CostSchema>>,
}

/// A cost–tolerance model `a + b / T^k` (Chase & Greenwood 1988).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CostSchema {
    pub a: Option<f64>,
    pub b: Option<f64>,
    pub k: Option<f64>,
    /// Largest tolerance allowed, in the parameter's unit or `"P%"`.
    pub max: Option<Spanned<toml::Value>>,
}
