//! Every consumer of an evaluation moves the estimate's stamps by the report's clock model (one
//! `ClockCorrection`): under a piecewise model (the shared `clock_step` mission, whose clock steps by
//! −0.5 s at 200 s) the figures and `ape --time-offset auto` follow the model, not the headline
//! constant. (The figures' half of this lives with the figures: `plot::mission`'s tests.)

use crate::common;

use std::process::Command;

#[test]
fn ape_with_an_automatic_offset_follows_a_piecewise_clock_model() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = shared.join("fixtures/clock_step");
    let ape = |extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
            .args(["ape", "tum"])
            .arg(dir.join("reference.tum"))
            .arg(dir.join("estimate.tum"))
            .arg("-as")
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        let rmse = out
            .lines()
            .find_map(|l| l.trim().strip_prefix("rmse"))
            .map(|v| v.trim().parse::<f64>().unwrap())
            .unwrap();
        (rmse, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (model, said) = ape(&["--time-offset", "auto"]);
    assert!(said.contains("clock model piecewise applied"), "{said}");
    // The headline constant alone (the offset of the longest segment) leaves the first 200 s 0.5 s
    // off: the model's APE is lower.
    let (headline, _) = ape(&["--t_offset", "-0.0999"]);
    assert!(model < 0.9 * headline, "model {model}, constant {headline}");
}
