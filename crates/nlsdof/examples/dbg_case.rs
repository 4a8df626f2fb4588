#[path = "../tests/support/synthetic.rs"]
mod synthetic;
use nlsdof::identification::equation_error::*;
use nlsdof::identification::models::*;
use nlsdof::identification::objective::FitSpec;
use nlsdof::identification::*;
fn main() {
    let seed: u64 = std::env::args().nth(1).unwrap().parse().unwrap();
    let c = synthetic::case(seed);
    println!("{}\ntruth {:?} phase {:?}", c.description, c.truth, c.phase);
    let spec = FitSpec::new(ModelKind::Generalised, &c.data);
    let prep = Prepared::new(&c.data, spec.scales).unwrap();
    let t = Terms {
        stiffness: true,
        damping: true,
        gain: None,
    };
    let (r, e) = (c.truth[RHO], c.truth[ETA]);
    if prep.has_phase() {
        let f = solve_phase(&prep, t, r, e, None, 0.0).unwrap();
        println!(
            "EE phase detect: {:?} cost {:e} phase {:?}",
            f.theta, f.cost, f.phase
        );
        let (s, off) = c.phase.unwrap();
        let f = solve_phase(
            &prep,
            t,
            r,
            e,
            Some(PhaseConvention {
                sign: s,
                offset: off,
                delay: 0.0,
            }),
            0.0,
        )
        .unwrap();
        println!("EE phase known: {:?} cost {:e}", f.theta, f.cost);
    }
    let (f, _) = solve_magnitude(&prep, t, r, e, None).unwrap();
    println!("EE magnitude: {:?} cost {:e}", f.theta, f.cost);
    let res = identify(&c.data, &FitPlan::new(ModelKind::Generalised), &|| {}).unwrap();
    println!(
        "landscape best {:?} minima {:?}",
        res.landscape
            .best()
            .map(|(i, j)| (res.landscape.rho[i], res.landscape.eta[j])),
        res.landscape
            .minima
            .iter()
            .take(5)
            .map(|&(i, j)| (
                res.landscape.rho[i],
                res.landscape.eta[j],
                res.landscape.at(i, j)
            ))
            .collect::<Vec<_>>()
    );
    println!("EE best {:?}", res.equation_error);
    for cand in &res.candidates {
        println!("cand {:?}", cand);
    }
    println!(
        "fit {:?} {:?} {}",
        res.fit.theta, res.fit.termination, res.fit.cost
    );
    let mut tt = c.truth;
    tt[GAIN] = 1.0;
    let e = nlsdof::identification::objective::evaluate_with_phase(
        &res.data,
        &tt,
        false,
        res.spec.phase_weight,
    )
    .unwrap();
    println!(
        "cost at truth {} ; fit unc {:?}",
        e.cost(),
        res.fit
            .uncertainty
            .as_ref()
            .map(|u| (u.names.clone(), u.lower.clone(), u.upper.clone()))
    );
    println!(
        "warning {:?} profile rho {:?} eta {:?}",
        res.fit.warning(),
        res.rho_profile,
        res.eta_profile
    );
}
#[allow(dead_code)]
fn unused() {}
