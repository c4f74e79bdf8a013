//! What a shard was computed from, and the settings every shard of one run shares.

use crate::model::{Case, Model, Sampling, SpeedRange};
use crate::montecarlo::McOptions;
use crate::quadrature::QuadOptions;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What a shard was computed from, section by section: for each top-level part of the
/// validated model (its serialisation, see [`Model`]: `name`, `parameters`, `gravity`,
/// `bodies`, `joints`, `forces`, `constraints`, `ports`, `independent`, `analysis`, …), the
/// tolerance cases run (`cases`) and each run setting (`speed`, `samples`, `seed`,
/// `sampling`, `quadrature`, and `quadrature_nodes` where asked), the first 32 hex digits of the SHA-256 of its canonical JSON.
/// Where the model was written (file, lines, columns, comments) is no part of it; every
/// number the model holds is, bit for bit. Two shards with equal fingerprints computed the
/// same numbers; where they differ, [`Fingerprint::differences`] names what.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fingerprint(pub BTreeMap<String, String>);

impl Fingerprint {
    /// The fingerprint of a run of `model` with `cases` and the settings `run` (its shard
    /// count left out: [`super::gather`] checks that).
    pub fn of(model: &Model, cases: &[Case], run: &RunSettings) -> Fingerprint {
        let mut sections = BTreeMap::new();
        let mut add = |name: &str, value: serde_json::Value| {
            let text = serde_json::to_string(&value).expect("a JSON value serialises");
            sections.insert(
                name.to_string(),
                crate::files::sha256_hex(text.as_bytes())[..32].to_string(),
            );
        };
        let model = serde_json::to_value(model).expect("a model serialises");
        let serde_json::Value::Object(parts) = model else {
            unreachable!("a model serialises to an object")
        };
        for (name, value) in parts {
            add(&name, value);
        }
        add("cases", json(&cases));
        add("speed", json(&run.speed));
        add("samples", json(&run.samples));
        add("seed", json(&run.seed));
        add("sampling", json(&run.sampling));
        add("quadrature", json(&run.quadrature.map(|q| q.tolerance)));
        // A section of its own, only where asked: the fingerprints of runs that leave the
        // quadrature's budget alone are what they were before it could be asked for.
        if let Some(n) = run.quadrature.and_then(|q| q.nodes) {
            add("quadrature_nodes", json(&n));
        }
        Fingerprint(sections)
    }

    /// The sections in which `other` differs from `self` (present in one only, or with
    /// another digest), as readers know them.
    pub fn differences(&self, other: &Fingerprint) -> Vec<&'static str> {
        let names: std::collections::BTreeSet<&String> =
            self.0.keys().chain(other.0.keys()).collect();
        let mut out: Vec<&'static str> = Vec::new();
        for k in names {
            let title = section_title(k);
            if self.0.get(k) != other.0.get(k) && !out.contains(&title) {
                out.push(title);
            }
        }
        out
    }
}

fn json(v: &impl Serialize) -> serde_json::Value {
    serde_json::to_value(v).expect("a plain value serialises")
}

/// What a fingerprint's section is called in messages.
fn section_title(section: &str) -> &'static str {
    match section {
        "name" => "model name",
        "parameters" => "parameters (values, tolerances, distributions; --set)",
        "gravity" => "gravity",
        "bodies" => "bodies",
        "joints" | "order" | "coordinates" => "joints",
        "forces" => "force elements",
        "constraints" => "constraints (cut joints)",
        "ports" => "ports",
        "loads" => "loads",
        "couplers" => "couplers",
        "requirements" => "requirements",
        "allocation" => "[allocation] table",
        "independent" => "independent coordinates",
        "analysis" => "[analysis] table",
        "cases" => "tolerance cases (--case)",
        "speed" => "speeds (--speed)",
        "samples" => "samples (--samples)",
        "seed" => "seed (--seed)",
        "sampling" => "sampling (--sampling)",
        "quadrature" | "quadrature_nodes" => {
            "quadrature options (--quadrature-tolerance, --quadrature-nodes, --no-quadrature)"
        }
        _ => "a part this version of modaltol does not know",
    }
}

/// The settings every shard of one run shares.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    /// The speed range, as `from:to:step` (rad/s).
    pub speed: String,
    pub samples: usize,
    pub seed: u64,
    pub sampling: Sampling,
    /// The quadrature's options; `None`: no quadrature.
    pub quadrature: Option<QuadOptions>,
    /// The number of shards.
    pub of: usize,
}

impl RunSettings {
    /// The settings of a sharded run over `speed` with the Monte Carlo options `mc`, the
    /// quadrature's options `quadrature` (`None`: none) split into `of` shards.
    pub fn new(
        speed: &SpeedRange,
        mc: &McOptions,
        quadrature: Option<QuadOptions>,
        of: usize,
    ) -> Self {
        RunSettings {
            speed: format!("{}:{}:{}", speed.from, speed.to, speed.step),
            samples: mc.samples,
            seed: mc.seed,
            sampling: mc.sampling,
            quadrature,
            of,
        }
    }
}
