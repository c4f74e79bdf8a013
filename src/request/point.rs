//! One operating point as asked for (`modal`, `sensitivity`, `frf`, `draw` and Python's point
//! methods): a speed, checked once, at the model's nominal parameters. The checks that make a
//! request bad input (a speed that is not finite, a model whose initial guess cannot be formed
//! there) are made here, before anything is solved, so that every front end refuses the same
//! requests for the same reasons; a point that is asked for well and does not solve is a
//! [`PointError`], reported as a failure of the run, not of its input.

use crate::compiled::Compiled;
use crate::settings;
use crate::sweep::{Options, Point, PointError, initial_guess, point_at};

/// Why a point request is refused (bad input, before anything is solved).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointRequestError {
    /// The speed is refused; the message leaves the setting unnamed (`--speed`, `speed`).
    #[error("{0}")]
    Speed(String),
    /// The model's initial guess cannot be formed at this speed (an initial coordinate that
    /// does not evaluate there).
    #[error("{0}")]
    Start(String),
}

/// A checked point request: the speed (rad/s) and the model's nominal parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct PointRequest {
    pub speed: f64,
    /// The model's nominal parameter values, where the point is solved.
    pub parameters: Vec<f64>,
}

impl PointRequest {
    /// Checks `speed` and that `model` gives an initial guess there.
    pub fn new(model: &Compiled, speed: f64) -> Result<PointRequest, PointRequestError> {
        let speed = settings::speed(speed).map_err(PointRequestError::Speed)?;
        let parameters = model.model().nominal();
        initial_guess(model.model(), &parameters, speed)
            .map_err(|e| PointRequestError::Start(e.to_string()))?;
        Ok(PointRequest { speed, parameters })
    }

    /// The point, solved from the model's initial guess with `opt`.
    pub fn solve(&self, model: &Compiled, opt: &Options) -> Result<Point, PointError> {
        point_at(model, &self.parameters, self.speed, opt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PENDULUM: &str = include_str!("../../examples/rotating_pendulum.toml");

    /// A speed that is not finite and an initial guess that does not evaluate are refused as
    /// bad input, each for its reason; a good request solves the point `point_at` solves.
    #[test]
    fn a_point_request_refuses_bad_input_and_solves_the_nominal_point() {
        let m = Compiled::from_str(PENDULUM, "pendulum.toml").unwrap();
        for w in [f64::NAN, f64::INFINITY] {
            assert!(matches!(
                PointRequest::new(&m, w),
                Err(PointRequestError::Speed(why)) if why.contains("finite")
            ));
        }
        let odd = PENDULUM.replace("initial = \"pi/3\"", "initial = \"1/(speed - 5)\"");
        let odd = Compiled::from_str(&odd, "pendulum.toml").unwrap();
        assert!(matches!(
            PointRequest::new(&odd, 5.0),
            Err(PointRequestError::Start(_))
        ));
        assert!(PointRequest::new(&odd, 4.0).is_ok());
        let request = PointRequest::new(&m, 4.0).unwrap();
        assert_eq!(request.parameters, m.model().nominal());
        let opt = Options::single();
        let solved = request.solve(&m, &opt).unwrap();
        let direct = point_at(&m, &m.model().nominal(), 4.0, &opt).unwrap();
        assert_eq!(solved.equilibrium.q, direct.equilibrium.q);
    }
}
