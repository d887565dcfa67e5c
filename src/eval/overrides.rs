//! Parameter overrides named like the `eval` flags, as batch manifests and presets write them in TOML
//! (`[defaults]`, `[mission.parameters]`, a preset's `[parameters]`).

use serde::Deserialize;

use crate::align::time_offset::OffsetMethod;
use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, Platform};
use crate::metrics::lever::LeverCorrection;
use crate::sources::StampSource;

/// Parameter overrides, named like the `eval` flags (`-` written `_`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Overrides {
    pub platform: Option<String>,
    pub eps_min: Option<f64>,
    pub curvature_eps: Option<f64>,
    pub path_eps: Option<f64>,
    pub theta_max: Option<f64>,
    pub dt_max: Option<f64>,
    pub window: Option<Vec<f64>>,
    pub overlap: Option<f64>,
    pub lever_correction: Option<String>,
    pub lever_arm: Option<f64>,
    pub offset_method: Option<String>,
    pub max_offset: Option<f64>,
    pub grid: Option<f64>,
    pub time_offset: Option<f64>,
    pub stamp: Option<String>,
    pub t_start: Option<f64>,
    pub t_end: Option<f64>,
    /// A manifest's `preset` (in `[defaults]` or `[mission.parameters]`): which topics to take. Not
    /// a parameter: [`Overrides::apply`] leaves it, and a preset's own `[parameters]` refuse it.
    pub preset: Option<String>,
}

impl Overrides {
    /// Applies the set values to `c`; an unknown word names the field and what it accepts.
    pub fn apply(&self, c: &mut EvalConfig) -> Result<()> {
        let bad = |field: &str, v: &str, ok: &str| {
            Error::InvalidArgument(format!("parameters: {field} = \"{v}\": expected {ok}"))
        };
        if let Some(p) = &self.platform {
            c.platform = match p.as_str() {
                "legged" => Platform::Legged,
                "wheeled" => Platform::Wheeled,
                "auto" => Platform::Auto,
                _ => return Err(bad("platform", p, "legged, wheeled or auto")),
            };
        }
        if let Some(m) = &self.offset_method {
            c.offset_method = match m.as_str() {
                "curvature" => OffsetMethod::Curvature,
                "speed" => OffsetMethod::Speed,
                _ => return Err(bad("offset_method", m, "curvature or speed")),
            };
        }
        if let Some(s) = &self.stamp {
            c.stamp = match s.as_str() {
                "header" => StampSource::Header,
                "log" => StampSource::Log,
                _ => return Err(bad("stamp", s, "header or log")),
            };
        }
        if let Some(l) = &self.lever_correction {
            c.lever_correction = l.parse::<LeverCorrection>()?;
        }
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut c.theta_max_rad, self.theta_max);
        set(&mut c.dt_max_s, self.dt_max);
        set(&mut c.overlap, self.overlap);
        set(&mut c.lever_arm_m, self.lever_arm);
        set(&mut c.max_offset_s, self.max_offset);
        set(&mut c.grid_s, self.grid);
        c.eps_min_m = self.eps_min.or(c.eps_min_m);
        c.curvature_eps_m = self.curvature_eps.or(c.curvature_eps_m);
        c.path_eps_m = self.path_eps.or(c.path_eps_m);
        c.time_offset_s = self.time_offset.or(c.time_offset_s);
        c.t_start = self.t_start.or(c.t_start);
        c.t_end = self.t_end.or(c.t_end);
        if let Some(w) = &self.window {
            c.windows_m = w.clone();
        }
        Ok(())
    }

    /// These overrides without the keys in `given` (flags the user set on the command line, which
    /// win over a preset's defaults). Keys are the field names, which are also the flags' clap ids.
    pub fn without(&self, given: &[String]) -> Overrides {
        let mut o = self.clone();
        for key in given {
            match key.as_str() {
                "platform" => o.platform = None,
                "eps_min" => o.eps_min = None,
                "curvature_eps" => o.curvature_eps = None,
                "path_eps" => o.path_eps = None,
                "theta_max" => o.theta_max = None,
                "dt_max" => o.dt_max = None,
                "window" => o.window = None,
                "overlap" => o.overlap = None,
                "lever_correction" => o.lever_correction = None,
                "lever_arm" => o.lever_arm = None,
                "offset_method" => o.offset_method = None,
                "max_offset" => o.max_offset = None,
                "grid" => o.grid = None,
                "time_offset" => o.time_offset = None,
                "stamp" => o.stamp = None,
                "t_start" => o.t_start = None,
                "t_end" => o.t_end = None,
                _ => {}
            }
        }
        o
    }
}
