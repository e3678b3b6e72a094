//! One orchestrator: the confusion battery's blind chain
//! (`rig_diagnose::diagnose_campaign`: calibrate → estimate → diagnose) runs
//! with the options the DAG's stages run, taken from the runner's parsed
//! pipeline.toml (`params_of`), and `BlindChain::from_pipeline_toml` (tests,
//! benches, examples) reads the same.

use rig_diagnose::BlindChain;
use rig_pipeline::Runner;
use rig_pipeline::testing::workspace_root;

/// The chain the confusion stage is handed: its `[stage.params.<stage>]`
/// copies of the three stages' params.
fn battery_chain(r: &Runner) -> BlindChain {
    let p = &r.config().stage("confusion").expect("stage confusion").params;
    let mut t = toml::Table::new();
    for name in ["campaign-calibration", "estimation", "diagnosis"] {
        let v = p.get(name).unwrap_or_else(|| panic!("confusion lacks params_of {name}"));
        t.insert(name.to_string(), v.clone());
    }
    toml::Value::Table(t).try_into().expect("the confusion stage's chain")
}

/// What the DAG's stages themselves are handed.
fn dag_chain(r: &Runner) -> BlindChain {
    let mut t = toml::Table::new();
    for name in ["campaign-calibration", "estimation", "diagnosis"] {
        t.insert(name.to_string(), toml::Value::Table(r.config().stage(name).unwrap().params.clone()));
    }
    toml::Value::Table(t).try_into().expect("the DAG's stages' params")
}

#[test]
fn the_blind_chain_runs_with_the_dags_options() {
    let path = workspace_root().join("pipeline.toml");
    let runner = Runner::new(&path).unwrap();
    let dag = dag_chain(&runner);
    assert_eq!(battery_chain(&runner), dag, "the confusion stage's chain vs the DAG's stages");
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(BlindChain::from_pipeline_toml(&text).unwrap(), dag, "from_pipeline_toml vs the runner's config");
}

/// A `--set` on a stage of the chain reaches the battery: the copy is made
/// again after it, so the battery never runs other options than the DAG.
#[test]
fn a_set_on_a_chain_stage_reaches_the_battery() {
    let path = workspace_root().join("pipeline.toml");
    let shipped = dag_chain(&Runner::new(&path).unwrap());
    assert_ne!(shipped.diagnosis.folds, 3, "the test must change the value");
    assert_ne!(shipped.estimation.whiteness_max_lag, 7, "the test must change the value");
    let set = Runner::new(&path)
        .unwrap()
        .set_param("diagnosis", "folds", "3")
        .unwrap()
        .set_param("estimation", "whiteness_max_lag", "7")
        .unwrap();
    let chain = battery_chain(&set);
    assert_eq!((chain.diagnosis.folds, chain.estimation.whiteness_max_lag), (3, 7));
    assert_eq!(chain, dag_chain(&set));
}

/// `params_of` is checked like `shared`: a missing stage and a stage
/// declaring the copy itself are refused, naming the stage.
#[test]
fn params_of_is_checked() {
    let base = std::fs::read_to_string(workspace_root().join("pipeline.toml")).unwrap();
    let cases = [
        (
            "params_of = [\"campaign-calibration\", \"estimation\", \"diagnosis\"]",
            "params_of = [\"diagnoses\"]",
            "params_of = [\"diagnoses\"]: no stage named diagnoses",
        ),
        (
            "seed = 7000",
            "seed = 7000\n[stage.params.diagnosis]\nfolds = 3",
            "[stage.params] diagnosis: the params of stage diagnosis come from params_of",
        ),
    ];
    for (from, to, expected) in cases {
        assert_eq!(base.matches(from).count(), 1, "{from}");
        let text = base.replacen(from, to, 1);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pipeline.toml");
        std::fs::write(&path, text).unwrap();
        let e = Runner::new(&path).err().expect("refused").to_string();
        assert!(e.contains("confusion") && e.contains(expected), "{e}");
    }
}
