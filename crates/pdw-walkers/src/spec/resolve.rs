//! Resolving a spec at parameter values ([`WalkerSpec::resolve`]): every field evaluated and
//! validated, in the order a reader meets them in the spec — the parameters, the builtins
//! (`slope`, `gravity`, `max_stride_time`), the leg's shape, the hip mass, the segments, the
//! feet, the knees, the gaits. The first field that breaks a rule is the error, naming it, its
//! value and the rule.

use super::{eval_expr, is_identifier, quoted, KneeSpec, Num, ParamTable, Resolved, WalkerSpec};
use crate::error::WalkerError;

/// The parameter values a spec's expressions are evaluated at, with the checks the fields share
/// (finite, `> 0`, `>= 0`); errors name the spec.
struct Env<'a> {
    spec: &'a WalkerSpec,
    vars: Vec<(&'a str, f64)>,
}

impl Env<'_> {
    /// A field's value: the number, or its expression evaluated; finite.
    fn eval(&self, field: &str, n: &Num) -> Result<f64, WalkerError> {
        let v = match n {
            Num::Value(v) => *v,
            Num::Expr(e) => {
                eval_expr(e, &self.vars).map_err(|msg| self.spec.err(field, quoted(e), msg))?
            }
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.spec.err(field, n.shown(v), "must be finite"))
        }
    }

    /// [`Env::eval`] of a field that must be `> 0`.
    fn positive(&self, field: &str, n: &Num) -> Result<f64, WalkerError> {
        let v = self.eval(field, n)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.spec.err(field, n.shown(v), "must be > 0"))
        }
    }

    /// [`Env::eval`] of a field that must be `>= 0`.
    fn nonneg(&self, field: &str, n: &Num) -> Result<f64, WalkerError> {
        let v = self.eval(field, n)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.spec.err(field, n.shown(v), "must be >= 0"))
        }
    }

    /// The value of parameter `name` (NaN if there is none).
    fn get(&self, name: &str) -> f64 {
        self.vars
            .iter()
            .find(|(n, _)| *n == name)
            .map(|p| p.1)
            .unwrap_or(f64::NAN)
    }
}

/// The knees of a resolved spec, per knee (foot side first): the knee fields of [`Resolved`].
struct Knees {
    free_swing: Vec<bool>,
    latched: Vec<bool>,
    latch_torque: Vec<Option<f64>>,
    latch_impulse: Vec<Option<f64>>,
}

impl WalkerSpec {
    /// Evaluates and validates the geometry at parameter values `values` (in
    /// [`WalkerSpec::param_table`] order).
    pub fn resolve(&self, values: &[f64]) -> Result<Resolved, WalkerError> {
        self.check_units(&self.name)?;
        let table = self.param_table();
        self.check_parameter_names()?;
        let env = self.env(&table, values)?;
        let (slope, gravity, max_stride_time) = self.builtins(&env)?;
        self.check_leg_shape()?;
        let hip_mass = env.nonneg("hip_mass", &self.hip_mass)?;
        let mut segments = Vec::with_capacity(self.segments.len());
        for i in 0..self.segments.len() {
            segments.push(self.resolve_segment(&env, i, hip_mass)?);
        }
        let foot_radius = self.resolve_foot_radius(&env, &segments)?;
        let knees = self.resolve_knees(&env)?;
        let gaits = self.resolve_gaits(&env)?;
        Ok(Resolved {
            slope,
            gravity,
            max_stride_time,
            step_down: env.get("step_down"),
            hip_mass,
            foot_radius,
            segments,
            free_swing: knees.free_swing,
            latched: knees.latched,
            latch_torque: knees.latch_torque,
            latch_impulse: knees.latch_impulse,
            gaits,
        })
    }

    /// Refuses a parameter name that is not an identifier (an expression could not name it).
    fn check_parameter_names(&self) -> Result<(), WalkerError> {
        for name in self.parameters.keys() {
            if !is_identifier(name) {
                return Err(self.err(
                    format!("parameters.{name}"),
                    name.clone(),
                    "a parameter name is a letter or _ followed by letters, digits or _",
                ));
            }
        }
        Ok(())
    }

    /// The table's names paired with `values`, every value finite (the slope, whose builtin
    /// default is NaN, must be given).
    fn env<'a>(&'a self, table: &'a ParamTable, values: &[f64]) -> Result<Env<'a>, WalkerError> {
        let vars: Vec<(&str, f64)> = table
            .names
            .iter()
            .map(|s| s.as_str())
            .zip(values.iter().copied())
            .collect();
        for (name, v) in &vars {
            if !v.is_finite() {
                let rule = if *name == "slope" {
                    "the spec must give the slope a default in [parameters] (or pass --slope)"
                } else {
                    "parameter values must be finite"
                };
                return Err(self.err(format!("parameters.{name}"), v.to_string(), rule));
            }
        }
        Ok(Env { spec: self, vars })
    }

    /// The builtins `(slope, gravity, max_stride_time)`: a slope in `(−π/2, π/2)`, a positive
    /// gravity and stride time.
    fn builtins(&self, env: &Env<'_>) -> Result<(f64, f64, f64), WalkerError> {
        let slope = env.get("slope");
        if slope.is_nan() || slope.abs() >= std::f64::consts::FRAC_PI_2 {
            return Err(self.err(
                "parameters.slope",
                slope.to_string(),
                "a slope in (-pi/2, pi/2) rad",
            ));
        }
        let gravity = env.get("gravity");
        if gravity.is_nan() || gravity <= 0.0 {
            return Err(self.err("parameters.gravity", gravity.to_string(), "must be > 0"));
        }
        let max_stride_time = env.get("max_stride_time");
        if max_stride_time.is_nan() || max_stride_time <= 0.0 {
            return Err(self.err(
                "parameters.max_stride_time",
                max_stride_time.to_string(),
                "must be > 0",
            ));
        }
        Ok((slope, gravity, max_stride_time))
    }

    /// Refuses a leg without segments and a knee count other than one between consecutive
    /// segments.
    fn check_leg_shape(&self) -> Result<(), WalkerError> {
        if self.segments.is_empty() {
            return Err(self.err(
                "segments",
                "[]",
                "a leg needs at least one segment ([[segments]] with length, mass, com)",
            ));
        }
        if self.knees.len() + 1 != self.segments.len() {
            let rule = if self.segments.len() == 1 {
                "a one-segment leg has no knee: remove [[knees]]".to_string()
            } else {
                format!(
                    "a leg of {} segments has {} knees (one between consecutive segments)",
                    self.segments.len(),
                    self.segments.len() - 1
                )
            };
            return Err(self.err("knees", format!("{} knees", self.knees.len()), rule));
        }
        Ok(())
    }

    /// Segment `i` as `[length, mass, com, com_normal, inertia]`: a positive length and mass,
    /// the COM on the segment, a non-negative inertia, and inertia about both joints (the hip
    /// mass `hip_mass` gives the top segment inertia about its lower joint).
    fn resolve_segment(
        &self,
        env: &Env<'_>,
        i: usize,
        hip_mass: f64,
    ) -> Result<[f64; 5], WalkerError> {
        let s = &self.segments[i];
        let f = |k: &str| format!("segments[{i}].{k}");
        let length = env.positive(&f("length"), &s.length)?;
        let mass = env.positive(&f("mass"), &s.mass)?;
        let com = env.eval(&f("com"), &s.com)?;
        let com_normal = env.eval(&f("com_normal"), &s.com_normal)?;
        let inertia = env.nonneg(&f("inertia"), &s.inertia)?;
        if !(0.0..=length).contains(&com) {
            return Err(self.err(
                f("com"),
                s.com.shown(com),
                format!(
                    "the COM is measured along the segment from its lower end, so it lies \
                     between 0 and the segment's length {length}; an offset off the segment \
                     line goes in com_normal"
                ),
            ));
        }
        let upper = length - com;
        // the hip mass sits at the top segment's upper end: it gives that segment inertia
        // about its lower joint in the stance leg
        let hip_here = i + 1 == self.segments.len() && hip_mass > 0.0;
        if (!hip_here && inertia + mass * (com * com + com_normal * com_normal) <= 0.0)
            || inertia + mass * (upper * upper + com_normal * com_normal) <= 0.0
        {
            return Err(self.err(
                f("com"),
                s.com.shown(com),
                "a segment with zero inertia about one of its joints (a point mass at a joint: \
                 COM at 0 or at the segment's length, on the segment line, inertia 0) makes \
                 the dynamics singular: move the COM or give an inertia",
            ));
        }
        Ok([length, mass, com, com_normal, inertia])
    }

    /// The round feet's radius: `>= 0`, less than the lowest segment's length, and not with
    /// the lowest segment's COM on the arc's centre without inertia.
    fn resolve_foot_radius(
        &self,
        env: &Env<'_>,
        segments: &[[f64; 5]],
    ) -> Result<f64, WalkerError> {
        let foot_radius = env.nonneg("foot_radius", &self.foot_radius)?;
        if foot_radius >= segments[0][0] {
            return Err(self.err(
                "foot_radius",
                self.foot_radius.shown(foot_radius),
                format!(
                    "the arc's centre must lie on the lowest segment: a radius in [0, {}) (the \
                     length of segments[0])",
                    segments[0][0]
                ),
            ));
        }
        let [_, m0, c0, cn0, i0] = segments[0];
        if foot_radius > 0.0 && i0 + m0 * ((c0 - foot_radius).powi(2) + cn0 * cn0) <= 0.0 {
            return Err(self.err(
                "foot_radius",
                self.foot_radius.shown(foot_radius),
                "the lowest segment's COM sits on the arc's centre with no inertia about it \
                 (singular): change the radius, move the COM or give an inertia",
            ));
        }
        Ok(foot_radius)
    }

    /// Every knee's mode, hold and holding limits; at most one free-swing knee.
    fn resolve_knees(&self, env: &Env<'_>) -> Result<Knees, WalkerError> {
        let mut free_swing = Vec::with_capacity(self.knees.len());
        let mut latched = Vec::with_capacity(self.knees.len());
        let mut latch_torque = Vec::with_capacity(self.knees.len());
        let mut latch_impulse = Vec::with_capacity(self.knees.len());
        for (i, k) in self.knees.iter().enumerate() {
            let free = self.knee_mode(env, i, k)?;
            free_swing.push(free);
            let latch = self.knee_hold(i, k)?;
            latched.push(latch);
            latch_torque.push(self.knee_limit(env, i, latch, "latch_torque", &k.latch_torque)?);
            latch_impulse.push(self.knee_limit(
                env,
                i,
                latch,
                "latch_impulse",
                &k.latch_impulse,
            )?);
            let limited = latch_torque[i].is_some() || latch_impulse[i].is_some();
            if limited && (self.segments.len() != 2 || !free) {
                return Err(self.err(
                    format!("knees[{i}]"),
                    format!(
                        "mode {}, {} segments",
                        quoted(k.mode.trim()),
                        self.segments.len()
                    ),
                    "a latch with holding limits needs a two-segment leg with a free-swing knee \
                     (mode = \"free-swing\"): a swing knee that lets go swings free until its \
                     knee strike; without limits a latch may hold any knee",
                ));
            }
        }
        if free_swing.iter().filter(|f| **f).count() > 1 {
            return Err(self.err(
                "knees",
                format!(
                    "{} free-swing knees",
                    free_swing.iter().filter(|f| **f).count()
                ),
                "at most one knee may be free-swing (one knee strike per step)",
            ));
        }
        Ok(Knees {
            free_swing,
            latched,
            latch_torque,
            latch_impulse,
        })
    }

    /// Whether knee `i` is free-swing: `"locked"`, `"free-swing"` (or `"free_swing"`), or an
    /// expression that evaluates to 0 (locked) or 1 (free-swing).
    fn knee_mode(&self, env: &Env<'_>, i: usize, k: &KneeSpec) -> Result<bool, WalkerError> {
        Ok(match k.mode.trim() {
            "locked" => false,
            "free-swing" | "free_swing" => true,
            e => match eval_expr(e, &env.vars) {
                Ok(0.0) => false,
                Ok(1.0) => true,
                Ok(v) => {
                    return Err(self.err(
                        format!("knees[{i}].mode"),
                        format!("{} = {v}", quoted(e)),
                        "an expression for a knee mode must be 0 (locked) or 1 (free-swing)",
                    ))
                }
                Err(msg) => {
                    return Err(self.err(
                        format!("knees[{i}].mode"),
                        quoted(e),
                        format!("\"locked\", \"free-swing\" or an expression (0 or 1): {msg}"),
                    ))
                }
            },
        })
    }

    /// Whether knee `i` is held by a latch (`hold = "latch"`) rather than a stop (`"stop"`,
    /// the default).
    fn knee_hold(&self, i: usize, k: &KneeSpec) -> Result<bool, WalkerError> {
        Ok(match k.hold.as_deref().map(str::trim) {
            None | Some("stop") => false,
            Some("latch") => true,
            Some(h) => {
                return Err(self.err(
                    format!("knees[{i}].hold"),
                    format!("\"{h}\""),
                    "\"stop\" (a hyper-extension stop that only pushes) or \"latch\" (holds \
                     both ways, up to latch_torque and latch_impulse when given)",
                ))
            }
        })
    }

    /// Knee `i`'s holding limit `key` (`latch_torque` or `latch_impulse`), if given: `>= 0`,
    /// and only on a latch (`latch`).
    fn knee_limit(
        &self,
        env: &Env<'_>,
        i: usize,
        latch: bool,
        key: &str,
        n: &Option<Num>,
    ) -> Result<Option<f64>, WalkerError> {
        let Some(n) = n else { return Ok(None) };
        let field = format!("knees[{i}].{key}");
        if !latch {
            return Err(self.err(
                field,
                n.to_string(),
                "a holding limit belongs to a latch: set hold = \"latch\" (a stop only \
                 pushes and holds no pull)",
            ));
        }
        env.nonneg(&field, n).map(Some)
    }

    /// The gait guesses `(name, section, source)`, each section three values evaluated.
    fn resolve_gaits(&self, env: &Env<'_>) -> Result<Vec<(String, Vec<f64>, String)>, WalkerError> {
        let mut gaits = Vec::with_capacity(self.gaits.len());
        for (i, g) in self.gaits.iter().enumerate() {
            if g.section.len() != 3 {
                return Err(self.err(
                    format!("gaits[{i}].section"),
                    format!("{} values", g.section.len()),
                    "three values: stance, stance_rate, hip_rate",
                ));
            }
            let mut sec = Vec::with_capacity(3);
            for (j, v) in g.section.iter().enumerate() {
                sec.push(env.eval(&format!("gaits[{i}].section[{j}]"), v)?);
            }
            gaits.push((g.name.clone(), sec, g.source.clone()));
        }
        Ok(gaits)
    }
}
