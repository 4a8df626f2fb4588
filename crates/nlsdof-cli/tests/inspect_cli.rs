//! `nlsdof inspect` end to end: the clamped beams (real data, skipped when
//! ../shared is absent), the demo's virtual wing (the `stepped-sine` rig on
//! `examples/har-wing.toml` at the demo's levels and band), the figure
//! policy, the help, and the bad-input contract.

mod common;

use common::{beam_dir, example, fails, json, ok, write};

/// The clamped-clamped beam without magnet: hardening (the README's
/// "strong Duffing hardening"; every up-run jumps down), the first line is
/// the verdict, JSON and text agree, the figure is written as SVG and PNG.
#[test]
fn clamped_beam_is_hardening() {
    let Some(dir) = beam_dir("cc_beam_no_magnet_24C") else {
        return;
    };
    let d = dir.to_str().unwrap();
    let text = ok(&["inspect", "--beam-dir", d]);
    let first = text.lines().next().unwrap();
    assert!(
        first.starts_with("nonlinear: hardening stiffness"),
        "{first}"
    );
    assert!(first.contains("nlsdof fit --model"), "{first}");
    let tmp = tempfile::tempdir().unwrap();
    let svg = tmp.path().join("beam.svg");
    let v = json(&[
        "inspect",
        "--beam-dir",
        d,
        "--json",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(v["headline"].as_str().unwrap(), first);
    assert_eq!(v["curves"].as_array().unwrap().len(), 6);
    assert_eq!(v["stiffness"]["hardening"], serde_json::json!(true));
    for c in v["curves"].as_array().unwrap() {
        assert_eq!(c["jump"]["kind"], serde_json::json!("drop"), "{c}");
    }
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(s.starts_with("<svg") && s.contains("backbone") && s.contains("delta_eq"));
    let png = tmp.path().join("beam.png");
    ok(&["inspect", "--beam-dir", d, "--plot", png.to_str().unwrap()]);
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    // both runs: 12 curves of 1024 points
    let v = json(&["inspect", "--beam-dir", d, "--runs", "both", "--json"]);
    assert_eq!(v["curves"].as_array().unwrap().len(), 12);
}

/// The cantilever (18 levels, no jump, resonance moving down 0.7 %):
/// softening, with the damping growing with the level.
#[test]
fn cantilever_is_softening() {
    let Some(dir) = beam_dir("cantilever_no_magnet") else {
        return;
    };
    let v = json(&["inspect", "--beam-dir", dir.to_str().unwrap(), "--json"]);
    assert_eq!(v["stiffness"]["hardening"], serde_json::json!(false));
    assert_eq!(v["levels"].as_array().unwrap().len(), 18);
    assert!(v["damping"]["nonlinear"].as_bool().unwrap());
    let eta = v["damping"]["fit"]["exponent"].as_f64().unwrap();
    assert!(eta > 0.0, "damping grows with the level: eta {eta}");
}

/// The demo's virtual wing: the stepped-sine rig on the Table 3 + Table 7
/// wing at the demo's five levels over 5.3–5.5 Hz. Hardening with
/// ρ ≈ 4 and η ≈ 3 (the model's 4.0022 and 3.031): both pinned.
#[test]
fn demo_wing_gives_the_model_exponents() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("wing.csv");
    ok(&[
        "stepped-sine",
        "--model",
        example("har-wing.toml").to_str().unwrap(),
        "--gamma",
        "0.41,0.62,0.81,1.00,1.23",
        "--f-min",
        "5.3",
        "--f-max",
        "5.5",
        "--steps",
        "200",
        "--out",
        csv.to_str().unwrap(),
    ]);
    let v = json(&["inspect", csv.to_str().unwrap(), "--json"]);
    assert_eq!(v["stiffness"]["hardening"], serde_json::json!(true));
    let rho = v["stiffness"]["fit"]["exponent"].as_f64().unwrap();
    let eta = v["damping"]["fit"]["exponent"].as_f64().unwrap();
    assert!((rho - 4.0022).abs() < 0.05, "rho {rho}");
    assert!((eta - 3.031).abs() < 0.05, "eta {eta}");
    assert_eq!(
        v["recommendation"]["model"],
        serde_json::json!("generalised")
    );
    assert_eq!(v["phase"]["used"], serde_json::json!(true));

    // `fit --from-inspect`: inspect's exponents, as `inspect` reports them,
    // beside the fit's; the race also starts from the landscape node
    // nearest to them (default grid 41 x 41 over rho 0..10, eta -1..8:
    // nodes 0.25 and 0.225 apart), and the fit still finds the wing's
    // exponents
    let f = json(&["fit", csv.to_str().unwrap(), "--from-inspect", "--json"]);
    let fi = &f["from_inspect"];
    assert_eq!(fi["rho"]["inspect"].as_f64().unwrap(), rho);
    assert_eq!(fi["eta"]["inspect"].as_f64().unwrap(), eta);
    let node = &fi["start_node"];
    let (nr, ne) = (node["rho"].as_f64().unwrap(), node["eta"].as_f64().unwrap());
    assert!((nr - rho).abs() <= 0.125 + 1e-9, "node rho {nr} vs {rho}");
    assert!((ne - eta).abs() <= 0.1125 + 1e-9, "node eta {ne} vs {eta}");
    let fit_rho = fi["rho"]["fit"].as_f64().unwrap();
    assert!((fit_rho - 4.0022).abs() < 0.05, "fit rho {fit_rho}");
    assert!(fi["rho"]["fit_free"].as_bool().unwrap());
    let text = ok(&["fit", csv.to_str().unwrap(), "--from-inspect"]);
    assert!(
        text.contains("From inspect") && text.contains("landscape node rho = "),
        "{text}"
    );
    // a model that holds both exponents takes no extra start
    let d = json(&[
        "fit",
        csv.to_str().unwrap(),
        "--model",
        "duffing",
        "--from-inspect",
        "--json",
    ]);
    assert!(
        d["from_inspect"]["start_node"].is_null(),
        "{}",
        d["from_inspect"]
    );
    assert!(!d["from_inspect"]["rho"]["fit_free"].as_bool().unwrap());
    // without the flag there is no such section
    let plain = json(&["fit", csv.to_str().unwrap(), "--json"]);
    assert!(plain.get("from_inspect").is_none());
}

#[test]
fn help_teaches_the_sections() {
    let h = ok(&["inspect", "--help"]);
    for s in [
        "PER CURVE",
        "HOMOGENEITY",
        "STIFFNESS AND DAMPING LAWS",
        "RECOMMENDATION",
        "g(mu)",
        "--beam-dir",
        "--gamma-in-g",
        "--plot",
    ] {
        assert!(h.contains(s), "--help lacks {s}");
    }
}

/// Bad input: one line on stderr, exit 2, nothing written.
#[test]
fn bad_input_is_one_line_and_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let mut s = String::from("level,gamma,f_hz,amplitude\n");
    for l in ["a", "b"] {
        for i in 0..20 {
            s.push_str(&format!("{l},1,{},0.001\n", 10.0 + 0.1 * i as f64));
        }
    }
    let flat = write(tmp.path(), "flat.csv", &s);
    let fig = tmp.path().join("fig.svg");
    let flat = flat.to_str().unwrap();
    let e = fails(
        &["inspect", flat, "--plot", fig.to_str().unwrap()],
        "constant",
        &fig,
    );
    assert!(e.contains("level a") && e.contains("Hz"), "{e}");
    let pdf = tmp.path().join("fig.pdf");
    fails(
        &["inspect", flat, "--plot", pdf.to_str().unwrap()],
        ".svg or .png",
        &pdf,
    );
    let none = tmp.path().join("absent.csv");
    fails(&["inspect", none.to_str().unwrap()], "absent.csv", &fig);
    fails(
        &["inspect", flat, "--min-jump-ratio", "0.5"],
        "--min-jump-ratio",
        &fig,
    );
    fails(
        &["inspect", flat, "--phase-convention", "sideways,0"],
        "--phase-convention",
        &fig,
    );
}
