//! Every consumer of an evaluation moves the estimate's stamps by the report's clock model (one
//! `ClockCorrection`): under a piecewise model (the shared `clock_step` mission, whose clock steps by
//! −0.5 s at 200 s) the figures and `ape --time-offset auto` follow the model, not the headline
//! constant.

use crate::common;

use std::process::Command;

use trajdrift::align::clock_model::OffsetModel;
use trajdrift::eval::config::{EvalConfig, NamedInput};
use trajdrift::eval::evaluate_with_inputs;
use trajdrift::plot::{mission_figures, FigureData, Trajectories};
use trajdrift::report::json::Report;

/// The first time of the aligned estimate's speed series in the mission's figures.
fn speed_figure_start(report: &Report, inputs: &trajdrift::eval::inputs::Inputs) -> f64 {
    let estimates = inputs.named_estimates();
    let figures = mission_figures(
        report,
        &Trajectories {
            reference: &inputs.reference.trajectory,
            estimates: &estimates,
        },
    );
    figures
        .iter()
        .find_map(|f| match &f.data {
            FigureData::Speed(s) => s.estimate.first().map(|p| p.0),
            _ => None,
        })
        .expect("a speed figure")
}

#[test]
fn figures_follow_a_piecewise_clock_model() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = shared.join("fixtures/clock_step");
    let c = EvalConfig::new(
        Some(dir.join("mission.mcap")),
        NamedInput::topic("/reference/position"),
        vec![NamedInput::topic("/estimate/odom")],
    );
    let (report, inputs) = evaluate_with_inputs(&c, &|_| {}).unwrap();
    let o = &report.estimates[0].time_offset;
    assert_eq!(o.model, Some(OffsetModel::Piecewise), "{o:?}");
    let first_segment = o.segments[0].offset_s;
    // The same report with its model taken away: the figures then shift by the headline constant.
    let mut constant = report.clone();
    constant.estimates[0].time_offset.model = Some(OffsetModel::Constant);
    let moved = speed_figure_start(&report, &inputs) - speed_figure_start(&constant, &inputs);
    // The mission starts in the first segment: its offset, not the headline's, moved the estimate.
    assert!(
        (moved - (first_segment - o.applied_s)).abs() < 1e-6,
        "moved {moved} s; segments {:?}, applied {}",
        o.segments,
        o.applied_s
    );
}

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
