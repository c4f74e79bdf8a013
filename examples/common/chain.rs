//! The benchmark's chain family, shared by `examples/scale_chain.rs` and `tests/blade.rs`
//! (included by path: a file in a subdirectory of `examples/` is not an example of its own).

/// The chain of `n` segments: length 1 m, μ = 2 kg/m, EI = 50 N·m², springs `EI/h` between
/// segments and `2EI/h` at the clamp, flapping out of the plane of rotation.
pub fn chain(n: usize) -> String {
    let mut s = format!(
        "name = \"chain {n}\"\ngravity = [0, 0, 0]\n[parameters]\n\
         mu = {{ value = 2.0, tolerance = \"2%\" }}\nEI = {{ value = 50.0, tolerance = \"5%\" }}\n\
         h = {}\n[[bodies]]\nname = \"hub\"\nmass = 1\ninertia = [0.01, 0.01, 0.01]\n\
         cm = [0, 0, 0]\n[[joints]]\nname = \"spin\"\ntype = \"revolute\"\nparent = \"ground\"\n\
         child = \"hub\"\nat = [0, 0, 0]\naxis = [0, 0, 1]\ndrive = \"speed\"\n",
        1.0 / n as f64
    );
    for i in 0..n {
        let parent = if i == 0 {
            "hub".into()
        } else {
            format!("s{}", i - 1)
        };
        let k = if i == 0 { "2*EI/h" } else { "EI/h" };
        s += &format!(
            "[[bodies]]\nname = \"s{i}\"\nmass = \"mu*h\"\n\
             inertia = [0, \"mu*h^3/12\", \"mu*h^3/12\"]\ncm = [\"{}*h\", 0, 0]\n\
             [[joints]]\nname = \"j{i}\"\ntype = \"revolute\"\nparent = \"{parent}\"\n\
             child = \"s{i}\"\nat = [\"{i}*h\", 0, 0]\naxis = [0, -1, 0]\nstiffness = \"{k}\"\n",
            i as f64 + 0.5
        );
    }
    s
}

/// The chain `text` of [`chain`] with a damper `α k` beside each joint spring `k` (so that
/// `Ĉ = α K̂` at rest: proportional damping, every mode's roots in closed form).
pub fn with_joint_dampers(text: &str, alpha: f64) -> String {
    text.replace(
        "stiffness = \"2*EI/h\"\n",
        &format!("stiffness = \"2*EI/h\"\ndamping = \"{alpha}*2*EI/h\"\n"),
    )
    .replace(
        "stiffness = \"EI/h\"\n",
        &format!("stiffness = \"EI/h\"\ndamping = \"{alpha}*EI/h\"\n"),
    )
}

/// The chain of [`chain`] with its first `k` segments' own `mu_i` (2 %) and `EI_i` (5 %), every
/// one toleranced on its own and independent (`2k` toleranced variables); the other segments
/// keep the shared `mu` and `EI`, with no tolerance. A segment's spring is its own `EI_i` over
/// `h` (twice that at the clamp), its mass and inertia its own `mu_i`'s.
pub fn chain_toleranced(n: usize, k: usize) -> String {
    assert!(k <= n, "at most one set of parameters a segment");
    let mut s = chain(n)
        .replace("mu = { value = 2.0, tolerance = \"2%\" }", "mu = 2.0")
        .replace("EI = { value = 50.0, tolerance = \"5%\" }", "EI = 50.0");
    let own: String = (0..k)
        .map(|i| {
            format!(
                "mu_{i} = {{ value = 2.0, tolerance = \"2%\" }}\n\
                 EI_{i} = {{ value = 50.0, tolerance = \"5%\" }}\n"
            )
        })
        .collect();
    s = s.replacen("h = ", &format!("{own}h = "), 1);
    // Segment i's block runs from its `[[bodies]]` header to the next one.
    let mut out = String::new();
    for (i, block) in s.split("[[bodies]]\nname = \"s").enumerate() {
        if i == 0 {
            out += block;
            continue;
        }
        let seg = i - 1;
        let block = if seg < k {
            block
                .replace("\"mu*h", &format!("\"mu_{seg}*h"))
                .replace("\"2*EI/h\"", &format!("\"2*EI_{seg}/h\""))
                .replace("\"EI/h\"", &format!("\"EI_{seg}/h\""))
        } else {
            block.to_string()
        };
        out += "[[bodies]]\nname = \"s";
        out += &block;
    }
    out
}

/// How the toleranced parameters of [`chain_family`] enter the chain: issue 55's families,
/// written the way engineers write a segmented blade.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coupling {
    /// Each joint's spring the harmonic mean of its two segments' bending stiffness,
    /// `2·EI_a·EI_b/(EI_a + EI_b)/h`: every `EI` enters two joints.
    Neighbours,
    /// A toleranced density factor `rho` in every segment's mass and inertia, beside the own
    /// `mu_i` and `EI_i` (each `EI` in one joint).
    Global,
    /// Gravity along the spin axis (it bends the blade out of its plane of rotation, so the
    /// equilibrium moves with every parameter), with `rho` and the harmonic-mean springs.
    Moving,
}

/// The `n`-segment chain of [`chain`] whose first `k` segments carry their own toleranced
/// `mu_i` (2 %) and `EI_i` (5 %) (the rest the shared, untoleranced `mu` and `EI`), entering as
/// `coupling` says: `2k` toleranced variables, `2k + 1` with `rho` (1 %).
pub fn chain_family(n: usize, k: usize, coupling: Coupling) -> String {
    assert!(k <= n, "at most one set of parameters a segment");
    let gravity = if coupling == Coupling::Moving {
        "[0, 0, -9.81]"
    } else {
        "[0, 0, 0]"
    };
    let global = coupling != Coupling::Neighbours;
    let harmonic = coupling != Coupling::Global;
    let mut s = format!("name = \"chain {n}, {k} toleranced segments, {coupling:?}\"\n");
    s += &format!(
        "gravity = {gravity}\n[parameters]\nmu = 2.0\nEI = 50.0\nh = {}\n",
        1.0 / n as f64
    );
    for i in 0..k {
        s += &format!(
            "mu_{i} = {{ value = 2.0, tolerance = \"2%\" }}\n\
             EI_{i} = {{ value = 50.0, tolerance = \"5%\" }}\n"
        );
    }
    s += if global {
        "rho = { value = 1.0, tolerance = \"1%\" }\n"
    } else {
        "rho = 1.0\n"
    };
    s += "[[bodies]]\nname = \"hub\"\nmass = 1\ninertia = [0.01, 0.01, 0.01]\n\
          cm = [0, 0, 0]\n[[joints]]\nname = \"spin\"\ntype = \"revolute\"\n\
          parent = \"ground\"\nchild = \"hub\"\nat = [0, 0, 0]\naxis = [0, 0, 1]\n\
          drive = \"speed\"\n";
    let own = |name: &str, i: usize| {
        if i < k {
            format!("{name}_{i}")
        } else {
            name.to_string()
        }
    };
    for i in 0..n {
        let parent = if i == 0 {
            "hub".into()
        } else {
            format!("s{}", i - 1)
        };
        let (mu, ei) = (own("mu", i), own("EI", i));
        let k_joint = if i == 0 {
            format!("2*{ei}/h")
        } else if harmonic {
            let before = own("EI", i - 1);
            format!("2*{before}*{ei}/({before} + {ei})/h")
        } else {
            format!("{ei}/h")
        };
        s += &format!(
            "[[bodies]]\nname = \"s{i}\"\nmass = \"rho*{mu}*h\"\n\
             inertia = [0, \"rho*{mu}*h^3/12\", \"rho*{mu}*h^3/12\"]\ncm = [\"{}*h\", 0, 0]\n\
             [[joints]]\nname = \"j{i}\"\ntype = \"revolute\"\nparent = \"{parent}\"\n\
             child = \"s{i}\"\nat = [\"{i}*h\", 0, 0]\naxis = [0, -1, 0]\nstiffness = \"{k_joint}\"\n",
            i as f64 + 0.5
        );
    }
    s
}
