//! Reading a scenario file into a [`Scenario`]: the TOML document with
//! edits and overrides written over it, `[model]` and `[planner]` taken out
//! by their `kind`, every number against its schema, the start and goal in
//! SI units, then the checks that span tables.

use super::*;

impl Scenario {
    /// Write `edits` over the parsed file (see [`Scenario::replace`]).
    pub(super) fn apply_edits<'i>(
        path: &Path,
        text: &str,
        root: &mut Spanned<DeTable<'i>>,
        edits: &'i [Edit],
    ) -> Result<(), Error> {
        if edits.is_empty() {
            return Ok(());
        }
        let lines = KeyIndex::new(text, &DeTable::default());
        for (kp, value) in edits {
            let t = root.get_mut();
            let anchor = keypath::anchor(t, kp);
            let line = (anchor.end > 0).then(|| lines.line_at(anchor.start));
            let err = |m: String| Error::keyed(path, line, &kp.to_string(), m);
            if let keypath::Found::Unreachable(why) = keypath::find(t, kp) {
                return Err(err(format!("cannot be set: {why}")));
            }
            let v = DeValue::parse(value)
                .map_err(|e| {
                    err(format!(
                        "`{value}` is not a TOML value: {}",
                        e.message().trim()
                    ))
                })?
                .into_inner();
            keypath::set(t, kp, v, anchor.clone()).map_err(|e| err(e.to_string()))?;
        }
        Ok(())
    }

    /// [`Scenario::parse`] with `edits` ([`Scenario::replace`]) and then
    /// numbers written over the file's (a variant: `[sweep]` is dropped; the
    /// `[sweep.vary]` paths are checked by `parse`).
    pub(super) fn parse_with(
        path: &Path,
        text: &str,
        edits: &[Edit],
        overrides: &[(KeyPath, f64)],
    ) -> Result<Scenario, Error> {
        let numbers: Vec<String> = overrides
            .iter()
            .map(|(_, x)| keypath::toml_number(*x))
            .collect();
        let mut root = DeTable::parse(text).map_err(|e| KeyIndex::syntax_error(path, text, &e))?;
        Self::apply_edits(path, text, &mut root, edits)?;
        if !overrides.is_empty() {
            let t = root.get_mut();
            // Inserted keys point at the [sweep] table that sets them.
            let span = t.get("sweep").map(|s| s.span()).unwrap_or(0..0);
            t.remove("sweep");
            for ((kp, _), n) in overrides.iter().zip(&numbers) {
                let v = DeValue::parse(n)
                    .map_err(|e| Error::keyed(path, None, &kp.to_string(), format!("{n}: {e}")))?
                    .into_inner();
                keypath::set(t, kp, v, span.clone())
                    .map_err(|e| Error::input(path, e.to_string()))?;
            }
        }
        let keys = KeyIndex::new(text, root.get_ref());
        keys.check_finite(path)?;
        let serde = |e: toml::de::Error| keys.serde_error(path, &e);
        let mut root = root.into_inner();
        let (model_kind, mut model) =
            take_tagged(&keys, path, &mut root, "model", ModelConfig::KINDS)?;
        if let Some((_, world)) = root.remove_entry("world") {
            world_obstacles(&keys, path, world, &mut model)?;
        }
        let urdf_source = take_urdf_source(&mut model).map_err(serde)?;
        let (planner_kind, planner) =
            take_tagged(&keys, path, &mut root, "planner", PlannerConfig::KINDS)?;
        // Match model and planner before reading the planner's parameters: a
        // wrong `kind` explains the parameters the other planner lacks.
        if !config::plans_for(&model_kind, &planner_kind) {
            return Err(keys.setup_error(path, &config::mismatch(&model_kind, &planner_kind)));
        }
        let rest = Spanned::new(0..text.len(), DeValue::Table(root));
        let file = ScenarioFile::deserialize(ValueDeserializer::from(rest)).map_err(serde)?;
        let model = ModelConfig::parse(&model_kind, model)
            .map_err(serde)?
            .ok_or_else(|| {
                keys.error_at(
                    path,
                    "model.kind",
                    format!("unknown model {}", crate::echo::code(&model_kind)),
                )
            })?;
        let mut planner = PlannerConfig::parse(&planner_kind, planner)
            .map_err(serde)?
            .ok_or_else(|| {
                keys.error_at(
                    path,
                    "planner.kind",
                    format!("unknown planner {}", crate::echo::code(&planner_kind)),
                )
            })?;
        // Every number against its documented range (the reference pages
        // show the same schemas).
        let ranges = |schema: &schema::Schema, value: Result<serde_json::Value, _>, prefix| {
            let value = value.map_err(|e: serde_json::Error| keys.error_at(path, prefix, e))?;
            schema
                .check(&value, prefix)
                .map_err(|e| keys.setup_error(path, &e))
        };
        ranges(file_schema(), serde_json::to_value(&file), "")?;
        if let Some(s) = ModelConfig::schema(&model_kind) {
            ranges(s, serde_json::to_value(&model), "model")?;
        }
        if let Some(s) = PlannerConfig::schema(&planner_kind) {
            ranges(s, serde_json::to_value(&planner), "planner")?;
        }
        let name = scenario_name(&keys, path, &file)?;
        let expect_fails = expectation(&keys, path, &file)?;
        let base = path.parent().unwrap_or(Path::new("."));
        planner.set_base(base);
        let system = build_system(&model, &planner).map_err(|e| keys.setup_error(path, &e))?;
        let urdf = base.join(model.urdf());
        if !urdf.exists() {
            return Err(keys.error_at(
                path,
                "model.urdf",
                format!("file not found: {}", crate::echo::path(&urdf)),
            ));
        }
        let (start, goal, max_rate) = start_goal_and_rates(&keys, path, &file, system.as_ref())?;
        check_across_tables(&keys, path, &file, &model, base)?;
        let regression = with_margin_tolerances(&file);
        Ok(Scenario {
            path: path.to_path_buf(),
            name,
            description: file.description.unwrap_or_default(),
            expect_fails,
            model,
            urdf,
            urdf_source: crate::engine::urdf::Source {
                packages: urdf_source
                    .packages
                    .iter()
                    .map(|(k, d)| (k.clone(), base.join(d)))
                    .collect(),
                xacro_args: urdf_source.xacro_args,
                missing_packages: urdf_source.missing_packages,
            },
            start,
            goal,
            planner,
            max_rate,
            ramp: file.limits.ramp,
            sim: file.sim,
            thresholds: file.thresholds,
            minimums: file.minimums,
            sweep: file.sweep,
            regression,
            margins: file.margins,
            compare: file.compare,
            keys: Arc::new(keys),
            text: text.into(),
            edits: edits.into(),
        })
    }
}

/// The keys of [`UrdfSourceConfig`], taken out of a `[model]` table.
fn take_urdf_source(model: &mut Spanned<DeValue<'_>>) -> Result<UrdfSourceConfig, toml::de::Error> {
    let span = model.span();
    let DeValue::Table(t) = model.get_mut() else {
        return Ok(UrdfSourceConfig::default());
    };
    let mut own = DeTable::new();
    for k in ["packages", "xacro_args", "missing_packages"] {
        if let Some((key, v)) = t.remove_entry(k) {
            own.insert(key, v);
        }
    }
    UrdfSourceConfig::deserialize(ValueDeserializer::from(Spanned::new(
        span,
        DeValue::Table(own),
    )))
}

/// `[[world.obstacles]]`: the same list as `[[model.obstacles]]` (the
/// models with obstacles read it there), written where the world is.
fn world_obstacles<'i>(
    keys: &KeyIndex,
    path: &Path,
    mut world: Spanned<DeValue<'i>>,
    model: &mut Spanned<DeValue<'i>>,
) -> Result<(), Error> {
    let DeValue::Table(w) = world.get_mut() else {
        return Err(keys.error_at(path, "world", "expected a table (`[[world.obstacles]]`)"));
    };
    if let Some(other) = w.keys().find(|k| k.get_ref() != "obstacles") {
        return Err(keys.error_at(
            path,
            &format!("world.{}", other.get_ref()),
            "unknown key (expected `obstacles`)",
        ));
    }
    let Some(obstacles) = w.remove("obstacles") else {
        return Ok(());
    };
    let DeValue::Table(m) = model.get_mut() else {
        return Ok(());
    };
    if m.contains_key("obstacles") {
        return Err(keys.error_at(
            path,
            "world.obstacles",
            "also given as `[[model.obstacles]]`: keep one list",
        ));
    }
    m.insert(Spanned::new(0..0, "obstacles".into()), obstacles);
    Ok(())
}

/// Remove the tagged table `name` (`[model]`, `[planner]`) from the document:
/// its `kind` and the rest of the table.
fn take_tagged<'i>(
    keys: &KeyIndex,
    path: &Path,
    root: &mut DeTable<'i>,
    name: &str,
    kinds: &[&str],
) -> Result<(String, Spanned<DeValue<'i>>), Error> {
    let known = kinds.join(", ");
    let Some((_, mut v)) = root.remove_entry(name) else {
        return Err(Error::Input {
            key: None,
            path: path.into(),
            line: Some(1),
            message: format!(
                "key `{name}`: required table is missing (`[{name}]` with `kind` = {known})"
            ),
        });
    };
    let DeValue::Table(t) = v.get_mut() else {
        return Err(keys.error_at(path, name, "expected a table with `kind`"));
    };
    let kind = match t.remove("kind").map(|k| k.into_inner()) {
        Some(DeValue::String(s)) => s.to_string(),
        Some(_) => {
            return Err(keys.error_at(
                path,
                &format!("{name}.kind"),
                format!("expected a string, one of {known}"),
            ))
        }
        None => {
            return Err(keys.error_at(
                path,
                &format!("{name}.kind"),
                format!("required key is missing (one of {known})"),
            ))
        }
    };
    if !kinds.contains(&kind.as_str()) {
        return Err(keys.error_at(
            path,
            &format!("{name}.kind"),
            format!(
                "unknown {name} {} (known: {known})",
                crate::echo::code(&kind)
            ),
        ));
    }
    Ok((kind, v))
}

/// The scenario's name: `name`, or the file's stem; either becomes the log
/// directory's name.
fn scenario_name(keys: &KeyIndex, path: &Path, file: &ScenarioFile) -> Result<String, Error> {
    match &file.name {
        Some(n) => {
            if let Some(p) = name_problem(n) {
                return Err(keys.error_at(
                    path,
                    "name",
                    format!("{} {p}: it is the log directory name", crate::echo::code(n)),
                ));
            }
            Ok(n.clone())
        }
        None => {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            if let Some(p) = name_problem(&stem) {
                return Err(keys.error_at(
                    path,
                    "name",
                    format!(
                        "not set, and the file name {} {p}: it would be the log directory name",
                        crate::echo::code(&stem)
                    ),
                ));
            }
            Ok(stem)
        }
    }
}

/// Why the scenario is meant to fail (`expect = "fails"` with its `reason`).
fn expectation(keys: &KeyIndex, path: &Path, file: &ScenarioFile) -> Result<Option<String>, Error> {
    match (file.expect, &file.reason) {
        (Some(Expect::Fails), Some(r)) if !r.trim().is_empty() => Ok(Some(r.trim().to_string())),
        (Some(Expect::Fails), _) => Err(keys.error_at(
            path,
            "expect",
            "`expect = \"fails\"` needs a `reason` (why the scenario is meant to fail)",
        )),
        (_, Some(_)) => Err(keys.error_at(
            path,
            "reason",
            "only with `expect = \"fails\"` (the reason a scenario is meant to fail)",
        )),
        _ => Ok(None),
    }
}

/// The checks that span tables: perturbations, margins, a sweep with its
/// model and margins, regression tolerances, a recording with a sweep.
fn check_across_tables(
    keys: &KeyIndex,
    path: &Path,
    file: &ScenarioFile,
    model: &ModelConfig,
    base: &Path,
) -> Result<(), Error> {
    let typed = |e: crate::error::SetupError| keys.setup_error(path, &e);
    file.sim.perturb.validate().map_err(typed)?;
    file.margins.validate().map_err(typed)?;
    if let Some(sw) = &file.sweep {
        sw.validate().map_err(typed)?;
        if !file.margins.gates().is_empty() {
            return Err(keys.error_at(path, "margins", "a sweep's verdict is its success rate over the variants; margins are searched and gated on single runs (drop [sweep] or [margins])"));
        }
        if sw.sigma_rate.is_some() && !matches!(model, ModelConfig::Rover(_)) {
            return Err(keys.error_at(
                path,
                "sweep.sigma_rate",
                format!(
                    "model `{}` has no switching signal σ (rover only)",
                    model.kind()
                ),
            ));
        }
    }
    file.regression.validate().map_err(typed)?;
    if let Some(c) = &file.compare {
        if file.sweep.is_some() {
            return Err(keys.error_at(
                path,
                "compare",
                "a recording is of one run; a sweep's variants are not it (drop [sweep] or [compare])",
            ));
        }
        if !c.time_offset.is_finite() {
            return Err(keys.error_at(
                path,
                "compare.time_offset",
                "must be a finite number of seconds",
            ));
        }
        crate::recording::Source::parse(&c.reference, base)
            .map_err(|e| keys.error_at(path, "compare.reference", e))?;
    }
    Ok(())
}

/// `[regression]` with each gated margin's default tolerance added.
fn with_margin_tolerances(file: &ScenarioFile) -> crate::scenario::regression::RegressionConfig {
    // Margins are coarse (a search to a resolution): their own default tolerance.
    let mut regression = file.regression.clone();
    for (d, _) in file.margins.gates() {
        regression
            .metrics
            .entry(MarginsConfig::metric(d))
            .or_insert(crate::scenario::regression::Tolerance {
                rel: Some(file.margins.tolerance()),
                abs: None,
            });
    }
    regression
}

/// `start`, `goal` and `max_rate`, in that order.
type StartGoalRates = (Vec<f64>, Vec<f64>, Vec<f64>);

/// `start` and `goal` in SI units (written in the system's file chart,
/// usually the model state, angles in degrees) and `[limits] max_rate`
/// (the system's default when not written), each checked for its length.
fn start_goal_and_rates(
    keys: &KeyIndex,
    path: &Path,
    file: &ScenarioFile,
    system: &dyn crate::robots::System,
) -> Result<StartGoalRates, Error> {
    // start/goal are written in the system's file chart (usually the model state).
    let chart = system.file_model();
    let (n_state, n_input) = (
        chart.state_names().len(),
        system.model().input_names().len(),
    );
    let angular = chart.angular_states();
    let default_rate = system.default_max_rate();
    let to_si = |key: &str, v: &[f64]| -> Result<Vec<f64>, Error> {
        if v.len() != n_state {
            return Err(keys.error_at(
                path,
                key,
                format!(
                    "expected {n_state} values ({}), got {}",
                    chart.state_names().join(", "),
                    v.len()
                ),
            ));
        }
        Ok(v.iter()
            .enumerate()
            .map(|(i, x)| {
                if angular.contains(&i) {
                    x.to_radians()
                } else {
                    *x
                }
            })
            .collect())
    };
    let start = system.state_from_file(to_si("start", &file.start)?);
    let goal = system.state_from_file(to_si("goal", &file.goal)?);
    let max_rate = file.limits.max_rate.clone().unwrap_or(default_rate);
    if max_rate.len() != n_input {
        return Err(keys.error_at(
            path,
            "limits.max_rate",
            format!("expected {n_input} values, got {}", max_rate.len()),
        ));
    }
    if let Some(i) = max_rate.iter().position(|r| *r <= 0.0) {
        return Err(keys.error_at(path, &format!("limits.max_rate[{i}]"), "rates must be > 0"));
    }
    Ok((start, goal, max_rate))
}
