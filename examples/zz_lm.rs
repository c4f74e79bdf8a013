use modaltol::model::Model;
use modaltol::sweep::{Options, Sweep, initial_guess, point};
use modaltol::tolerance::local_model;
fn main() {
    let what = std::env::args().nth(1).unwrap();
    let model = Model::from_file(std::path::Path::new("examples/governor.toml")).unwrap();
    let p = model.nominal();
    let w = 1.595;
    let q0 = initial_guess(&model, &p, w).unwrap();
    let pt = point(&model, &p, w, &q0, &Options::default()).unwrap();
    let k = model.parameter("spring_k").unwrap();
    let tf = model.analysis.transfer.as_ref();
    match what.as_str() {
        "lm1" => {
            for _ in 0..1000 {
                local_model(&model, &p, &pt, &[k], tf, true).unwrap();
            }
        }
        "lm3" => {
            for _ in 0..300 {
                local_model(&model, &p, &pt, &model.toleranced(), tf, true).unwrap();
            }
        }
        "sweep" => {
            for _ in 0..20 {
                let mut s = Sweep::new(&model, p.clone(), Options::default());
                for i in 0..501 {
                    s.step(i as f64 * 0.01).unwrap();
                }
            }
        }
        _ => {}
    }
}
