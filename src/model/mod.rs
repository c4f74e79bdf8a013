//! Model files: the TOML format, expressions, and validation into an immutable [`Model`].
//!
//! Raw text → [`schema`] (serde mirror, with spans) → `validate` → [`Model`]. Nothing
//! downstream sees a raw string reference: bodies, joints and parameters are indices, numeric
//! fields are parsed [`Expr`]essions with the [`Site`] they came from, so a failure at run time
//! (say a division by zero at one speed) can still name the file, line and field.

pub mod admissible;
pub mod expr;
pub mod judged;
pub mod schema;
mod symmetry;
pub mod table;
mod validate;
mod warnings;

mod analysis;
mod frames;
mod requirements;
mod site;

pub use admissible::Defect;
pub use analysis::{
    Analysis, Case, Channel, Correlation, Distribution, Sampling, SpeedRange, Tolerance, Transfer,
};
pub use expr::{EvalError, Expr};
pub use requirements::{Allocation, Cost, Requirement};
pub use site::{Field, FieldError, ModelError, Site};

use std::path::Path;

/// A named model parameter (a candidate design variable).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Parameter {
    pub name: String,
    pub value: f64,
    pub tolerance: Option<Tolerance>,
    pub distribution: Distribution,
    #[serde(skip)]
    pub site: Site,
}

/// A parameter defined by an expression of other parameters (`[parameters] h = "L/10"`).
#[derive(Debug, Clone)]
pub struct Derived {
    pub name: String,
    /// The expression as written.
    pub text: String,
    /// The expression over the (base) parameters, derived ones put in place.
    pub expr: Expr,
    /// Its value at the nominal parameters.
    pub value: f64,
    pub site: Site,
}

/// A rigid body. Inertia is about the centre of mass, in global axes of the reference
/// configuration; `cm` is the centre of mass there.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Body {
    pub name: String,
    pub mass: Field,
    /// About the centre of mass, in the body's inertia axes.
    pub inertia: [[Field; 3]; 3],
    /// The inertia axes' x and y directions in the reference configuration (z completes a
    /// right-handed frame; y is made orthogonal to x); `None`: the global axes.
    pub axes: Option<[[Field; 3]; 2]>,
    pub cm: [Field; 3],
}

/// A tree joint: `child` moves relative to `parent` (`None` = ground) with the joint's
/// coordinates; its type ([`crate::joints`]) says how.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Joint {
    pub name: String,
    pub kind: crate::joints::Kind,
    pub parent: Option<usize>,
    pub child: usize,
    pub geometry: crate::joints::Geometry<[Field; 3]>,
    /// Per coordinate: the initial guess of the equilibrium (rad or m).
    pub initial: Vec<Field>,
    /// Constant coordinate speed (rad/s or m/s) when driven (one-coordinate joints only).
    pub drive: Option<Field>,
    /// Per coordinate: spring rate (N·m/rad or N/m), its free coordinate value, and damping
    /// (N·m·s/rad or N·s/m).
    pub stiffness: Vec<Option<Field>>,
    pub free: Vec<Field>,
    pub damping: Vec<Option<Field>>,
    /// Indices of this joint's coordinates (empty for a fixed joint).
    pub coords: std::ops::Range<usize>,
}

/// A generalised coordinate: one relative coordinate of one joint.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Coordinate {
    pub joint: usize,
    /// The joint's name, or `joint.suffix` for joints with several coordinates.
    pub name: String,
    pub unit: crate::joints::Unit,
    pub driven: bool,
}

/// A force element between two bodies; its type ([`crate::forces`]) gives its deformation's
/// components, and each component its own spring, damper, free value and preload.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ForceElement {
    pub name: String,
    pub kind: crate::forces::Kind,
    pub geometry: crate::forces::Geometry<[Field; 3]>,
    /// Per component (`None`: zero).
    pub stiffness: Vec<Option<Field>>,
    pub damping: Vec<Option<Field>>,
    /// Per component; `None`: the deformation in the reference configuration.
    pub free: Vec<Option<Field>>,
    pub preload: Vec<Option<Field>>,
    /// The off-diagonal terms of the stiffness and damping matrices, where they are given
    /// as matrices (each pair of components once, `None`: zero).
    pub cross: Vec<CrossField>,
}

/// An off-diagonal term of a force element's stiffness and damping matrices (see
/// [`crate::mechanics::Cross`]).
#[derive(Debug, Clone, serde::Serialize)]
pub struct CrossField {
    pub row: usize,
    pub col: usize,
    pub stiffness: Option<Field>,
    pub damping: Option<Field>,
}

/// A cut joint closing a kinematic loop; its type ([`crate::cuts`]) gives its equations.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Constraint {
    pub name: String,
    pub kind: crate::cuts::Kind,
    pub geometry: crate::cuts::Geometry<[Field; 3], Field>,
    /// Its equations (indices within it) that are redundant at the reference configuration
    /// and not imposed (a planar loop's out-of-plane equations, say).
    pub dropped: Vec<usize>,
}

/// A physical degree of freedom of a body where a transfer function may start or end: a
/// point along a direction (a force in, the point's displacement along it out) or a direction
/// alone (a torque about it in, the body's rotation about it out). The direction is carried
/// by the body, as drawn.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Port {
    pub name: String,
    pub body: usize,
    pub point: [Field; 3],
    pub direction: [Field; 3],
    pub rotation: bool,
}

/// An unbalance (`[[unbalances]]`): a mass `m` at a distance `e` from the spin axis of a
/// spinning body, given as `magnitude = m e` (kg·m) at `point` (on the axis, reference
/// configuration) and an angle `phase` (rad) about the spin from the body's reference
/// direction. It turns with the body: a force of amplitude `m e Ω²` at the spin rate `Ω`,
/// `F = m e Ω² e^{iφ} (e₁ − i e₂)` across the spin axis `n` (`e₂ = n × e₁`), ROSS's
/// `run_unbalance_response`. A transfer function's input, never its output.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Unbalance {
    pub name: String,
    pub body: usize,
    pub point: [Field; 3],
    pub magnitude: Field,
    pub phase: Field,
}

/// A coupler (`[[couplers]]`): the linear relation `a q₁ + b q₂ = c` between two free joint
/// coordinates (a gear pair, a rack and pinion, a belt), imposed like a cut joint's equation.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Coupler {
    pub name: String,
    /// The two coordinates (indices).
    pub coordinates: [usize; 2],
    /// `a`, `b`.
    pub coefficients: [Field; 2],
    /// `c`.
    pub value: Field,
}

/// An applied load (`[[loads]]`): a constant force or torque on a body, or a generalised force
/// on a joint coordinate, each component an expression of the parameters (so it can carry a
/// tolerance).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Load {
    pub name: String,
    pub kind: LoadKind,
}

/// What a load applies, and where.
#[derive(Debug, Clone, serde::Serialize)]
pub enum LoadKind {
    /// A force (N) at `point` of `body` (given in the reference configuration): its components
    /// in ground axes (a dead load, `follower = false`) or in the body's axes as drawn, turning
    /// with it (a follower load).
    Force {
        body: usize,
        point: Box<[Field; 3]>,
        force: Box<[Field; 3]>,
        follower: bool,
    },
    /// A torque (N·m) on `body`, in ground axes or turning with the body.
    Torque {
        body: usize,
        torque: Box<[Field; 3]>,
        follower: bool,
    },
    /// A generalised force on a free joint coordinate (N·m on an angle, N on a length).
    Coordinate { coordinate: usize, value: Field },
}

/// A beam element (`[[beams]]`; the mechanics is [`crate::beams`]): node `a` at `point1` of
/// `body1`, node `b` at `point2` of `body2` (reference configuration; `None` is ground), the
/// section's second axis taken from `reference` (made perpendicular to the chord).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Beam {
    pub name: String,
    pub body1: Option<usize>,
    pub point1: [Field; 3],
    pub body2: Option<usize>,
    pub point2: [Field; 3],
    pub reference: [Field; 3],
    pub section: BeamSection,
    /// Stiffness-proportional material damping `β` (s): each deformation component's force is
    /// `k (e + β ė)`. `None`: undamped.
    pub damping: Option<Field>,
}

/// How a beam's section is given (SI units).
#[derive(Debug, Clone, serde::Serialize)]
pub enum BeamSection {
    /// A circular tube of one isotropic material.
    Tube(Box<TubeSection>),
    /// Section properties.
    Properties(Box<SectionProperties>),
}

/// A circular tube of one isotropic material: outer and inner diameter (m), Young's modulus
/// (Pa), the shear modulus (Pa) or Poisson's ratio, density (kg/m³), and the shear coefficient
/// (Cowper's for the hollow circle, from Poisson's ratio, where not given).
#[derive(Debug, Clone, serde::Serialize)]
pub struct TubeSection {
    pub outer: Field,
    pub inner: Option<Field>,
    pub youngs: Field,
    pub shear_modulus: Option<Field>,
    pub poisson: Option<Field>,
    pub density: Field,
    pub coefficient: Option<Field>,
}

/// A beam's section properties: `EA` (N), `GJ`, `[EI₂, EI₃]` (N·m²), the shear stiffnesses
/// `[κGA₂, κGA₃]` (N; none: Euler–Bernoulli), `ρA` (kg/m) and `[ρJ, ρI₂, ρI₃]` (kg·m).
#[derive(Debug, Clone, serde::Serialize)]
pub struct SectionProperties {
    pub ea: Field,
    pub gj: Field,
    pub ei: [Field; 2],
    pub kga: Option<[Field; 2]>,
    pub rho_a: Field,
    pub rho_i: [Field; 3],
}

/// A validated mechanism. Immutable; numbers are expressions of the parameters and speed.
///
/// Its serialisation is everything that can change a number computed from it (every body,
/// joint, force, constraint, port, expression, the gravity, the independent coordinates and
/// the `[analysis]` table) and nothing of where it was written (file, lines, columns): what
/// the fingerprint of a shard ([`crate::shard::Fingerprint`]) hashes.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Model {
    pub name: String,
    #[serde(skip)]
    pub file: String,
    pub parameters: Vec<Parameter>,
    /// Parameters defined by expressions of others (`h = "L/10"`), in file order: put in place
    /// of their names wherever they are used, so they are not design variables of their own
    /// (and what uses them is hashed through its fields).
    #[serde(skip)]
    pub derived: Vec<Derived>,
    pub gravity: [Field; 3],
    pub bodies: Vec<Body>,
    pub joints: Vec<Joint>,
    /// Joint indices with every parent before its children.
    pub order: Vec<usize>,
    pub coordinates: Vec<Coordinate>,
    pub forces: Vec<ForceElement>,
    /// Beam elements (`[[beams]]`), in file order.
    pub beams: Vec<Beam>,
    pub constraints: Vec<Constraint>,
    /// Named ports for transfer functions between physical points.
    pub ports: Vec<Port>,
    /// Applied loads (`[[loads]]`), in file order.
    pub loads: Vec<Load>,
    /// Unbalances (`[[unbalances]]`), in file order: inputs of transfer functions.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unbalances: Vec<Unbalance>,
    /// Couplers between joint coordinates (`[[couplers]]`), in file order: their equations
    /// follow the cut joints'.
    pub couplers: Vec<Coupler>,
    /// User's choice of independent coordinates (coordinate indices), if any.
    pub independent: Option<Vec<usize>>,
    pub analysis: Analysis,
    /// What a design must meet (`[[requirements]]`), in file order.
    pub requirements: Vec<Requirement>,
    /// The yield target and cost model of tolerance allocation (`[allocation]`).
    pub allocation: Allocation,
}

/// Why an unbalance's transfer function takes no `order`.
pub const UNBALANCE_ORDER: &str = "an unbalance excites at its own body's spin rate (which may \
    be any multiple of the speed): `order` does not apply";

impl Case {
    /// The case made of the tolerances declared on the parameters themselves.
    pub fn from_parameters(model: &Model) -> Case {
        Case {
            name: "parameters".into(),
            tolerances: model
                .parameters
                .iter()
                .enumerate()
                .filter_map(|(i, p)| p.tolerance.map(|t| (i, t)))
                .collect(),
            correlation: None,
        }
    }
}

impl Model {
    /// Largest model file accepted (bytes): real models are a few kilobytes.
    pub const MAX_FILE_BYTES: u64 = 4 << 20;

    /// Reads and validates a model file.
    pub fn from_file(path: &Path) -> Result<Model, ModelError> {
        Model::from_file_with(path, &[])
    }

    /// Reads and validates a model file with the nominal values of some parameters replaced
    /// (see [`Model::from_bytes_with`]).
    pub fn from_file_with(path: &Path, overrides: &[(String, f64)]) -> Result<Model, ModelError> {
        let file = path.display().to_string();
        // Bounded whatever the file is: a device or a pipe has no size to check beforehand.
        let bytes =
            crate::files::read_bounded(path, Self::MAX_FILE_BYTES).map_err(|e| ModelError {
                file: file.clone(),
                line: None,
                column: None,
                message: match e.source.kind() {
                    std::io::ErrorKind::InvalidData => format!(
                        "the file is larger than {} MiB; model files are limited to {} MiB",
                        Self::MAX_FILE_BYTES >> 20,
                        Self::MAX_FILE_BYTES >> 20
                    ),
                    _ => format!("cannot read the model file: {}", e.source),
                },
                snippet: None,
            })?;
        Model::from_bytes_with(&bytes, &file, overrides)
    }

    /// Validates a model given as bytes; `file` names it in messages.
    pub fn from_bytes(bytes: &[u8], file: &str) -> Result<Model, ModelError> {
        Model::from_bytes_with(bytes, file, &[])
    }

    /// Validates a model given as bytes with the nominal values of some parameters replaced
    /// (`(name, value)`, applied in order): the same model as the file edited to say so.
    pub fn from_bytes_with(
        bytes: &[u8],
        file: &str,
        overrides: &[(String, f64)],
    ) -> Result<Model, ModelError> {
        if bytes.len() as u64 > Self::MAX_FILE_BYTES {
            return Err(ModelError {
                file: file.to_string(),
                line: None,
                column: None,
                message: format!(
                    "the model is {} bytes; the limit is {} MiB",
                    bytes.len(),
                    Self::MAX_FILE_BYTES >> 20
                ),
                snippet: None,
            });
        }
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let off = e.valid_up_to();
            let prefix = String::from_utf8_lossy(&bytes[..off]).into_owned();
            validate::error_at(file, &prefix, off, "the file is not valid UTF-8 text")
        })?;
        validate::validate(text, file, overrides)
    }

    /// Validates a model given as text; `file` names it in messages.
    pub fn from_str(text: &str, file: &str) -> Result<Model, ModelError> {
        validate::validate(text, file, &[])
    }

    /// Nominal parameter values.
    pub fn nominal(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.value).collect()
    }

    /// The joints' initial coordinates at parameters `p` and `speed`: where Newton starts.
    pub fn initial_guess(&self, p: &[f64], speed: f64) -> Result<Vec<f64>, FieldError> {
        let mut q = vec![0.0; self.coordinates.len()];
        for j in &self.joints {
            for (k, c) in j.coords.clone().enumerate() {
                q[c] = j.initial[k].eval(p, speed)?;
            }
        }
        Ok(q)
    }

    /// Where the model's equations may be recorded ([`crate::program::Program::record`]), in
    /// the order to try them: its nominal parameters at the first, middle and last speeds of
    /// its `[analysis] speed` (0 without one), each with its initial guess there; a speed where
    /// the initial guess does not evaluate is left out. The model alone decides them.
    pub fn reference_points(&self) -> Vec<(Vec<f64>, f64, Vec<f64>)> {
        let p = self.nominal();
        let mut speeds = match self.analysis.speed {
            Some(r) if !r.is_empty() => vec![r.at(0), r.at(r.len() / 2), r.at(r.len() - 1)],
            _ => vec![0.0],
        };
        speeds.dedup_by(|a, b| a.to_bits() == b.to_bits());
        (speeds.into_iter())
            .filter_map(|w| Some((p.clone(), w, self.initial_guess(&p, w).ok()?)))
            .collect()
    }

    /// Indices of the parameters that carry a tolerance: the default design variables.
    pub fn toleranced(&self) -> Vec<usize> {
        (0..self.parameters.len())
            .filter(|&i| self.parameters[i].tolerance.is_some())
            .collect()
    }

    /// Index of a parameter by name.
    pub fn parameter(&self, name: &str) -> Option<usize> {
        self.parameters.iter().position(|p| p.name == name)
    }

    /// Index of the coordinate of the joint named `name`.
    pub fn coordinate(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c.name == name)
    }

    /// The transfer-function end named `name`: a free coordinate, a port or an unbalance.
    pub fn channel(&self, name: &str) -> Option<Channel> {
        match self.coordinate(name) {
            Some(c) if !self.coordinates[c].driven => Some(Channel::Coordinate(c)),
            Some(_) => None,
            None => (self.ports.iter().position(|p| p.name == name))
                .map(Channel::Port)
                .or_else(|| {
                    (self.unbalances.iter().position(|u| u.name == name)).map(Channel::Unbalance)
                }),
        }
    }

    /// The name of a transfer-function end.
    pub fn channel_name(&self, c: Channel) -> &str {
        match c {
            Channel::Coordinate(i) => &self.coordinates[i].name,
            Channel::Port(i) => &self.ports[i].name,
            Channel::Unbalance(i) => &self.unbalances[i].name,
        }
    }

    /// The units of a transfer-function end: of its response and of its excitation (an
    /// unbalance's excitation is the response's own scale: `H` is the response).
    pub fn channel_units(&self, c: Channel) -> (&'static str, &'static str) {
        use crate::joints::Unit;
        let unit = match c {
            Channel::Coordinate(i) => self.coordinates[i].unit,
            Channel::Port(i) if self.ports[i].rotation => Unit::Angle,
            Channel::Port(_) | Channel::Unbalance(_) => Unit::Length,
        };
        (unit.symbol(), unit.force_symbol())
    }

    /// The unit of `|H|` of a transfer function: response per excitation, e.g. `m/N` or
    /// `rad/(N·m)`; the response's own unit where an unbalance excites (`m`).
    pub fn transfer_unit(&self, t: &Transfer) -> String {
        let (response, _) = self.channel_units(t.output);
        let (_, excitation) = self.channel_units(t.input);
        if matches!(t.input, Channel::Unbalance(_)) {
            response.to_string()
        } else if excitation.contains('·') {
            format!("{response}/({excitation})")
        } else {
            format!("{response}/{excitation}")
        }
    }

    /// The input and output of a frequency response, `input=NAME,output=NAME` (or `model`):
    /// as [`Model::parse_transfer`], refusing `order`, which means nothing for a response over
    /// a range of excitation frequencies, and an unbalance, which excites at its spin only.
    pub fn parse_response(&self, spec: &str) -> Result<Transfer, String> {
        if spec
            .split(',')
            .any(|p| p.split('=').next().map(str::trim) == Some("order"))
        {
            return Err(
                "`order` does not apply to a frequency response (the excitation frequencies \
                 are given as a range)"
                    .into(),
            );
        }
        let t = self.parse_transfer(spec)?;
        if let Channel::Unbalance(i) = t.input {
            return Err(format!(
                "'{}' is an unbalance: it excites at its body's spin only, so it has no \
                 response over a range of frequencies (use it in `sweep --transfer` or \
                 `[analysis] transfer`, the response along the speeds)",
                self.unbalances[i].name
            ));
        }
        Ok(t)
    }

    /// A transfer function from a spec `input=NAME,output=NAME[,order=X]` (names of free
    /// coordinates, ports or, as the input, an unbalance), or `model` for the model's
    /// `[analysis] transfer`.
    pub fn parse_transfer(&self, spec: &str) -> Result<Transfer, String> {
        if spec == "model" {
            return self
                .analysis
                .transfer
                .ok_or_else(|| "the model declares no [analysis] transfer".to_string());
        }
        let (mut input, mut output, mut order) = (None, None, None);
        for part in spec.split(',') {
            let (k, v) = part
                .split_once('=')
                .ok_or_else(|| format!("'{part}' is not key=value"))?;
            let channel = |v: &str| {
                self.channel(v.trim()).ok_or_else(|| {
                    format!(
                        "'{}' is neither a free joint coordinate, a port nor an unbalance",
                        v.trim()
                    )
                })
            };
            match k.trim() {
                "input" => input = Some(channel(v)?),
                "output" => output = Some(channel(v)?),
                "order" => {
                    order = Some(
                        v.trim()
                            .parse::<f64>()
                            .ok()
                            .filter(|o| o.is_finite() && *o >= 0.0)
                            .ok_or_else(|| format!("order '{v}' must be a number ≥ 0"))?,
                    )
                }
                _ => return Err(format!("unknown key '{k}' (input, output, order)")),
            }
        }
        let input = input.ok_or("needs input=NAME (a free coordinate, a port or an unbalance)")?;
        let output = output.ok_or("needs output=NAME (a free coordinate or a port)")?;
        if let Channel::Unbalance(i) = output {
            return Err(format!(
                "'{}' is an unbalance: a force in, it has no response to read (output a port \
                 or a free coordinate)",
                self.unbalances[i].name
            ));
        }
        if matches!(input, Channel::Unbalance(_)) && order.is_some() {
            return Err(UNBALANCE_ORDER.into());
        }
        Ok(Transfer {
            input,
            output,
            order: order.unwrap_or(1.0),
        })
    }

    /// Indices of driven coordinates.
    pub fn driven(&self) -> Vec<usize> {
        (0..self.coordinates.len())
            .filter(|&i| self.coordinates[i].driven)
            .collect()
    }

    /// Indices of free (not driven) coordinates, `q_R`.
    pub fn free(&self) -> Vec<usize> {
        (0..self.coordinates.len())
            .filter(|&i| !self.coordinates[i].driven)
            .collect()
    }

    /// The name of the cut joint or coupler each imposed constraint equation belongs to, in
    /// the order `Φ` stacks them (each cut joint's kept equations, then one per coupler): what
    /// a message about an equation names.
    pub fn equation_owners(&self) -> Vec<&str> {
        let cuts = self.constraints.iter().flat_map(|c| {
            std::iter::repeat_n(c.name.as_str(), c.kind.equations() - c.dropped.len())
        });
        cuts.chain(self.couplers.iter().map(|c| c.name.as_str()))
            .collect()
    }

    /// Which of the paper's two examples (Kim & Yoo 2007) this model is, if one: the rotating
    /// pendulum (parameters `m`, `L`, `c`, one degree of freedom, no loop) or the governor
    /// (`ball_mass`, `spring_k`, `attach`, two loops). Its comparisons with the paper (timings,
    /// "the paper's method") appear for those only.
    pub fn paper_example(&self) -> Option<&'static str> {
        let has = |names: &[&str]| names.iter().all(|n| self.parameter(n).is_some());
        if has(&["m", "L", "c"]) && self.dof() == 1 && self.constraints.is_empty() {
            Some("pendulum")
        } else if has(&["ball_mass", "spring_k", "attach"]) && self.n_constraints() == 2 {
            Some("governor")
        } else {
            None
        }
    }

    /// Number of scalar constraint equations imposed (the redundant ones dropped).
    pub fn n_constraints(&self) -> usize {
        self.constraints
            .iter()
            .map(|c| c.kind.equations() - c.dropped.len())
            .sum::<usize>()
            + self.couplers.len()
    }

    /// The design variables named (parameter indices), or, without names, those that carry a
    /// tolerance. An unknown name is an error naming it. So is a derived parameter: it is a
    /// function of the parameters it is made of, so a derivative with respect to it alone (the
    /// others held) is not defined; the message names them, the variables to ask for instead.
    pub fn design_variables(&self, names: Option<&[String]>) -> Result<Vec<usize>, String> {
        match names {
            Some(names) => names
                .iter()
                .map(|n| {
                    self.parameter(n)
                        .ok_or_else(|| self.not_a_design_variable(n))
                })
                .collect(),
            None => Ok(self.toleranced()),
        }
    }

    /// Why `name` is not a design variable: derived (from which parameters), or unknown.
    fn not_a_design_variable(&self, name: &str) -> String {
        let Some(d) = self.derived.iter().find(|d| d.name == name) else {
            return format!("unknown parameter '{name}'");
        };
        let from: Vec<&str> = (d.expr.parameters().into_iter())
            .map(|i| self.parameters[i].name.as_str())
            .collect();
        if from.is_empty() {
            return format!(
                "parameter '{name}' is derived (= \"{}\") and a constant: it is not a design variable",
                d.text
            );
        }
        format!(
            "parameter '{name}' is derived (= \"{}\") from {}: a function of them, not a design variable, so a derivative with respect to it alone is not defined; ask for {} instead",
            d.text,
            from.join(", "),
            if from.len() == 1 { "it" } else { "them" }
        )
    }

    /// Free coordinates named as the independent ones (coordinate indices): as many as the
    /// degrees of freedom, each a free joint coordinate, each once (the rule the model file's
    /// `independent` follows; a repeated name would leave a degree of freedom without one).
    pub fn independent_coordinates(&self, names: &[String]) -> Result<Vec<usize>, String> {
        let mut out: Vec<usize> = Vec::with_capacity(names.len());
        for n in names {
            let i = self
                .coordinate(n)
                .filter(|&i| !self.coordinates[i].driven)
                .ok_or_else(|| format!("'{n}' is not a free joint coordinate of the model"))?;
            if out.contains(&i) {
                return Err(format!("'{n}' is named twice"));
            }
            out.push(i);
        }
        if out.len() != self.dof() {
            return Err(format!(
                "{} coordinate(s) named but the model has {} degree(s) of freedom",
                out.len(),
                self.dof()
            ));
        }
        Ok(out)
    }

    /// The tolerance cases of `[analysis]` named in `only` (all of them when it is empty), or,
    /// when the model declares none, the one made of the parameters' own tolerances.
    pub fn tolerance_cases(&self, only: &[String]) -> Result<Vec<Case>, String> {
        let mut cases = self.analysis.cases.clone();
        if !only.is_empty() {
            let names: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
            if let Some(bad) = only.iter().find(|n| !names.contains(&n.as_str())) {
                return Err(format!(
                    "the model has no tolerance case '{bad}' (it has: {})",
                    names.join(", ")
                ));
            }
            cases.retain(|c| only.contains(&c.name));
        }
        if cases.is_empty() {
            let c = Case::from_parameters(self);
            if c.tolerances.is_empty() {
                return Err(
                    "the model declares no tolerance case and no parameter carries a tolerance"
                        .into(),
                );
            }
            cases.push(c);
        }
        Ok(cases)
    }

    /// Degrees of freedom: free coordinates minus constraint equations.
    pub fn dof(&self) -> usize {
        self.free().len().saturating_sub(self.n_constraints())
    }
}

#[cfg(test)]
mod tests;
