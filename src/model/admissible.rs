//! Physical admissibility of a parameter set: the checks the nominal model passes at load, for
//! any design (a Monte Carlo sample, a quadrature node, the ends of a tolerance range).
//!
//! A design is admissible when every number of the model that does not depend on the speed
//! evaluates to a finite value, no body has negative mass, every inertia is symmetric and
//! positive semi-definite, and every beam's section is physical (positive stiffnesses,
//! diameters and densities, an inner diameter below the outer one) and keeps its direction
//! (its nodes do not meet or cross). (Numbers that depend on
//! the speed are checked where they are evaluated, speed by speed, and a failure there fails
//! that speed with its reason.) A sample that is not admissible is a sample of a mechanism that
//! cannot exist: it counts as failed, with the reason, instead of entering the statistics with
//! a negative mass.

use super::{Field, Model};

/// Why a design is not admissible: the element and the defect (without the value, so that
/// reasons can be tallied), and the offending value.
#[derive(Debug, Clone, PartialEq)]
pub struct Defect {
    pub reason: String,
    pub value: f64,
}

impl std::fmt::Display for Defect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({:e})", self.reason, self.value)
    }
}

/// A model element: its kind and name.
#[derive(Clone, Copy)]
struct Element<'a>(&'static str, &'a str);

impl std::fmt::Display for Element<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.1 {
            "" => write!(f, "{}", self.0),
            name => write!(f, "{} '{name}'", self.0),
        }
    }
}

/// The length of beam `beam` along its nominal chord at the design `p`, where that is not
/// positive: its nodes meet or cross (a station's length toleranced through zero), which the
/// element would read as a beam turned end for end. Points that depend on the speed are
/// checked where they are evaluated.
fn reversed(beam: &super::Beam, p: &[f64], nominal: &[f64]) -> Option<f64> {
    let chord = |p: &[f64]| -> Option<[f64; 3]> {
        let mut c = [0.0; 3];
        for (k, x) in c.iter_mut().enumerate() {
            let (a, b) = (&beam.point1[k], &beam.point2[k]);
            if a.expr.uses_speed() || b.expr.uses_speed() {
                return None;
            }
            *x = b.eval(p, 0.0).ok()? - a.eval(p, 0.0).ok()?;
        }
        Some(c)
    };
    let (now, then) = (chord(p)?, chord(nominal)?);
    let norm = then.iter().map(|x| x * x).sum::<f64>().sqrt();
    let along = (0..3).map(|k| now[k] * then[k]).sum::<f64>() / norm;
    (along <= 0.0).then_some(along)
}

/// A beam section's defect at the design `p`, if any, as `(defect, value)`: a stiffness,
/// diameter or density not positive, a rotary inertia negative, an inner diameter not below
/// the outer one, Poisson's ratio outside (−1, ½). Fields that depend on the speed are checked
/// where they are evaluated.
fn section_defect(beam: &super::Beam, p: &[f64]) -> Option<(String, f64)> {
    let name = &beam.name;
    let value = |f: &Field| (!f.expr.uses_speed()).then(|| f.eval(p, 0.0).unwrap_or(f64::NAN));
    let not_positive = |f: &Field, zero: bool| {
        let v = value(f)?;
        (!(v > 0.0 || zero && v == 0.0)).then(|| (format!("{} is not positive", f.site.what), v))
    };
    match &beam.section {
        super::BeamSection::Tube(t) => {
            let positive = [&t.outer, &t.youngs, &t.density]
                .into_iter()
                .chain(t.shear_modulus.iter())
                .chain(t.coefficient.iter());
            if let Some(d) = positive.filter_map(|f| not_positive(f, false)).next() {
                return Some(d);
            }
            if let Some(inner) = &t.inner {
                if let Some(d) = not_positive(inner, true) {
                    return Some(d);
                }
                if let (Some(i), Some(o)) = (value(inner), value(&t.outer))
                    && i >= o
                {
                    let reason =
                        format!("beam '{name}': inner diameter not below the outer one (m)");
                    return Some((reason, i));
                }
            }
            let nu = t.poisson.as_ref().and_then(value);
            nu.filter(|v| !(*v > -1.0 && *v < 0.5)).map(|v| {
                (
                    format!("beam '{name}': Poisson's ratio outside (-1, 0.5)"),
                    v,
                )
            })
        }
        super::BeamSection::Properties(q) => [&q.ea, &q.gj, &q.rho_a]
            .into_iter()
            .chain(&q.ei)
            .chain(q.kga.iter().flatten())
            .filter_map(|f| not_positive(f, false))
            .chain(q.rho_i.iter().filter_map(|f| not_positive(f, true)))
            .next(),
    }
}

/// The inertia's defect, if any: not symmetric, or not positive semi-definite (eigenvalues
/// below `−1e-12 ×` the largest entry), as `(defect, value)`.
pub fn inertia_defect(i: &[[f64; 3]; 3]) -> Option<(&'static str, f64)> {
    let m = nalgebra::DMatrix::from_fn(3, 3, |r, c| i[r][c]);
    let scale = m.amax().max(1e-300);
    let asym = (&m - m.transpose()).amax();
    if asym > 1e-12 * scale {
        return Some(("inertia matrix is not symmetric", asym));
    }
    match crate::linalg::symmetric_eigen(m) {
        None => Some(("inertia eigenvalues could not be computed", scale)),
        Some(e) if e.eigenvalues.min() < -1e-12 * scale => Some((
            "inertia is not positive semi-definite (smallest eigenvalue, kg·m²)",
            e.eigenvalues.min(),
        )),
        Some(_) => None,
    }
}

impl Model {
    /// Every field with the element it belongs to, for checks over the whole model.
    fn fields(&self) -> Vec<(Element<'_>, &Field)> {
        let mut out: Vec<(Element<'_>, &Field)> = Vec::new();
        for f in &self.gravity {
            out.push((Element("gravity", ""), f));
        }
        for b in &self.bodies {
            let e = Element("body", &b.name);
            out.push((e, &b.mass));
            out.extend(b.inertia.iter().flatten().map(|f| (e, f)));
            out.extend(b.axes.iter().flatten().flatten().map(|f| (e, f)));
            out.extend(b.cm.iter().map(|f| (e, f)));
        }
        for j in &self.joints {
            let e = Element("joint", &j.name);
            let g = &j.geometry;
            out.extend(g.at.iter().chain(&g.axis).chain(&g.axis2).map(|f| (e, f)));
            out.extend(j.initial.iter().chain(&j.free).map(|f| (e, f)));
            out.extend(
                j.stiffness
                    .iter()
                    .chain(&j.damping)
                    .chain([&j.drive])
                    .flatten()
                    .map(|f| (e, f)),
            );
        }
        for s in &self.forces {
            let e = Element("force", &s.name);
            let g = &s.geometry;
            out.extend(
                g.point1
                    .iter()
                    .chain(&g.point2)
                    .chain(&g.axis)
                    .chain(&g.reference)
                    .map(|f| (e, f)),
            );
            out.extend(
                s.stiffness
                    .iter()
                    .chain(&s.damping)
                    .chain(&s.free)
                    .chain(&s.preload)
                    .chain(s.cross.iter().flat_map(|x| [&x.stiffness, &x.damping]))
                    .flatten()
                    .map(|f| (e, f)),
            );
        }
        for b in &self.beams {
            let e = Element("beam", &b.name);
            out.extend(
                b.point1
                    .iter()
                    .chain(&b.point2)
                    .chain(&b.reference)
                    .map(|f| (e, f)),
            );
            let section: Vec<&Field> = match &b.section {
                crate::model::BeamSection::Tube(t) => [&t.outer, &t.youngs, &t.density]
                    .into_iter()
                    .chain(
                        [&t.inner, &t.shear_modulus, &t.poisson, &t.coefficient]
                            .into_iter()
                            .flatten(),
                    )
                    .collect(),
                crate::model::BeamSection::Properties(p) => [&p.ea, &p.gj, &p.rho_a]
                    .into_iter()
                    .chain(&p.ei)
                    .chain(p.kga.iter().flatten())
                    .chain(&p.rho_i)
                    .collect(),
            };
            out.extend(section.into_iter().map(|f| (e, f)));
        }
        for c in &self.constraints {
            let e = Element("constraint", &c.name);
            let g = &c.geometry;
            out.extend(
                g.point1
                    .iter()
                    .chain(&g.point2)
                    .chain(&g.axis)
                    .chain(&g.axis2)
                    .chain(&g.length)
                    .map(|f| (e, f)),
            );
        }
        out
    }

    /// Checks that the design `p` is physically admissible (see the module documentation).
    pub fn admissible(&self, p: &[f64]) -> Result<(), Defect> {
        for (element, f) in self.fields() {
            if f.expr.uses_speed() {
                continue;
            }
            match f.eval(p, 0.0) {
                Ok(v) if v.is_finite() => {}
                Ok(v) => {
                    return Err(Defect {
                        reason: format!("{element}: {} is not finite", f.site.what),
                        value: v,
                    });
                }
                Err(e) => {
                    return Err(Defect {
                        reason: format!("{element}: {}: {}", f.site.what, e.error),
                        value: f64::NAN,
                    });
                }
            }
        }
        for b in &self.bodies {
            if !b.mass.expr.uses_speed() {
                let m = b.mass.eval(p, 0.0).unwrap_or(f64::NAN);
                if m < 0.0 {
                    return Err(Defect {
                        reason: format!("body '{}': negative mass (kg)", b.name),
                        value: m,
                    });
                }
            }
            if b.inertia.iter().flatten().all(|f| !f.expr.uses_speed()) {
                let i: [[f64; 3]; 3] = std::array::from_fn(|r| {
                    std::array::from_fn(|c| b.inertia[r][c].eval(p, 0.0).unwrap_or(f64::NAN))
                });
                if let Some((defect, value)) = inertia_defect(&i) {
                    return Err(Defect {
                        reason: format!("body '{}': {defect}", b.name),
                        value,
                    });
                }
            }
        }
        let nominal = (!self.beams.is_empty()).then(|| self.nominal());
        for b in &self.beams {
            if let Some((reason, value)) = section_defect(b, p) {
                return Err(Defect { reason, value });
            }
            if let Some(along) = nominal.as_ref().and_then(|n| reversed(b, p, n)) {
                return Err(Defect {
                    reason: format!(
                        "beam '{}': its nodes meet or cross (a length its tolerance makes zero or negative; m)",
                        b.name
                    ),
                    value: along,
                });
            }
        }
        Ok(())
    }

    /// For each tolerance case, a design within its tolerances that is not admissible, if one
    /// is found among the ends of each variable's range (±3σ of a normal variable, the bounds
    /// of a uniform one; one at a time, the others nominal) and
    /// the corners of the range box (up to 10 variables): the tolerance reaches a physical limit,
    /// and Monte Carlo samples beyond it will count as failed. Cases come from the model's
    /// `[analysis]`, or one made of the parameters' own tolerances.
    pub fn tolerance_limits(&self) -> Vec<(String, String, Defect)> {
        let mut cases = self.analysis.cases.clone();
        if cases.is_empty() {
            cases.push(super::Case::from_parameters(self));
        }
        let nominal = self.nominal();
        let mut out = Vec::new();
        for case in &cases {
            let ends: Vec<(usize, f64)> = case
                .tolerances
                .iter()
                .map(|(i, t)| (*i, t.absolute(self.parameters[*i].value)))
                .collect();
            let describe = |p: &[f64]| {
                ends.iter()
                    .filter(|(i, _)| p[*i].to_bits() != nominal[*i].to_bits())
                    .map(|(i, _)| format!("{} = {}", self.parameters[*i].name, p[*i]))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let mut designs: Vec<Vec<f64>> = Vec::new();
            for &(i, h) in &ends {
                for s in [-1.0, 1.0] {
                    let mut p = nominal.clone();
                    p[i] += s * h;
                    designs.push(p);
                }
            }
            if ends.len() <= 10 {
                for mask in 0..(1usize << ends.len()) {
                    let mut p = nominal.clone();
                    for (k, &(i, h)) in ends.iter().enumerate() {
                        p[i] += if mask >> k & 1 == 1 { h } else { -h };
                    }
                    designs.push(p);
                }
            }
            if let Some((p, d)) = designs
                .iter()
                .find_map(|p| self.admissible(p).err().map(|d| (p, d)))
            {
                out.push((case.name.clone(), describe(p), d));
            }
        }
        out
    }
}
