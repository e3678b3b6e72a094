//! Typed settings read from a pipeline.toml text, as the runner hands them to
//! a stage: the one reader for code that is not run by the DAG (tests, benches,
//! examples, the blind chain). pipeline.toml is the one home of every default;
//! code that needs a setting reads it here instead of writing the number again.

use serde::de::DeserializeOwned;

#[derive(serde::Deserialize)]
struct Stage {
    name: String,
    params: Option<toml::Value>,
    #[serde(default)]
    shared: Vec<String>,
}

#[derive(serde::Deserialize)]
struct File {
    #[serde(default)]
    stage: Vec<Stage>,
    #[serde(default)]
    shared: toml::Table,
}

fn parse(text: &str) -> Result<File, String> {
    toml::from_str(text).map_err(|e| format!("pipeline.toml: {e}"))
}

/// The `[stage.params]` of stage `name` in a pipeline.toml text, with the
/// `[shared.<name>]` tables it lists, as the runner hands them over
/// (`rig_pipeline`'s config; a test there checks the two agree).
pub fn stage_params<T: DeserializeOwned>(text: &str, name: &str) -> Result<T, String> {
    let f = parse(text)?;
    let st = f.stage.into_iter().find(|s| s.name == name).ok_or_else(|| format!("pipeline.toml: no stage `{name}`"))?;
    let mut params = st.params.ok_or_else(|| format!("pipeline.toml: stage {name} has no [stage.params]"))?;
    for shared in &st.shared {
        let table = f.shared.get(shared).ok_or_else(|| format!("pipeline.toml: no [shared.{shared}]"))?;
        if let toml::Value::Table(t) = &mut params {
            t.insert(shared.clone(), table.clone());
        }
    }
    params.try_into().map_err(|e| format!("pipeline.toml: stage {name}: [stage.params]: {e}"))
}

/// The `[shared.<name>]` table of a pipeline.toml text, typed: what every
/// stage that lists `name` is handed.
pub fn shared_table<T: DeserializeOwned>(text: &str, name: &str) -> Result<T, String> {
    let f = parse(text)?;
    let table = f.shared.get(name).cloned().ok_or_else(|| format!("pipeline.toml: no [shared.{name}]"))?;
    table.try_into().map_err(|e| format!("pipeline.toml: [shared.{name}]: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Tol {
        limit: f64,
    }

    #[derive(Debug, PartialEq, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Params {
        settle_s: f64,
        tol: Tol,
    }

    const TEXT: &str = "[shared.tol]\nlimit = 1e-8\n[[stage]]\nname = \"a\"\nshared = [\"tol\"]\n\
                        [stage.params]\nsettle_s = 3.0\n";

    #[test]
    fn a_shared_table_and_a_stage_with_it_are_read() {
        assert_eq!(shared_table::<Tol>(TEXT, "tol").unwrap(), Tol { limit: 1e-8 });
        assert_eq!(stage_params::<Params>(TEXT, "a").unwrap(), Params { settle_s: 3.0, tol: Tol { limit: 1e-8 } });
    }

    #[test]
    fn what_is_missing_or_misspelt_is_named() {
        assert_eq!(shared_table::<Tol>(TEXT, "tols").unwrap_err(), "pipeline.toml: no [shared.tols]");
        let e = shared_table::<Tol>(&TEXT.replace("limit", "limitl"), "tol").unwrap_err();
        assert!(e.starts_with("pipeline.toml: [shared.tol]: ") && e.contains("limitl"), "{e}");
        assert_eq!(stage_params::<Params>(TEXT, "b").unwrap_err(), "pipeline.toml: no stage `b`");
    }
}
