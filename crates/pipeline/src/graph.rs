//! The stage DAG: dependency order (deterministic), cycles, upstream closure
//! for `--only`, and the Mermaid / DOT text of `cargo xtask graph`.

use crate::config::{Input, PipelineConfig};
use crate::error::PipelineError;
use std::collections::BTreeSet;

/// Stage names in an order where every stage comes after its dependencies;
/// ties are broken by declaration order so the order never depends on hashing.
pub fn topological_order(config: &PipelineConfig) -> Result<Vec<String>, PipelineError> {
    let mut done: Vec<String> = Vec::new();
    let mut left: Vec<&crate::config::StageDecl> = config.stages.iter().collect();
    while !left.is_empty() {
        let pos = left.iter().position(|s| s.dependencies().iter().all(|d| done.contains(d)));
        match pos {
            Some(i) => done.push(left.remove(i).name.clone()),
            None => {
                let names: Vec<&str> = left.iter().map(|s| s.name.as_str()).collect();
                return Err(PipelineError::Config {
                    path: config.path.clone(),
                    stage: Some(names[0].to_string()),
                    reason: format!("dependency cycle among stages {}", names.join(", ")),
                });
            }
        }
    }
    Ok(done)
}

/// `names` and every stage they depend on, transitively.
pub fn with_upstream(config: &PipelineConfig, names: &[&str]) -> Result<BTreeSet<String>, PipelineError> {
    let mut set = BTreeSet::new();
    let mut todo: Vec<String> = Vec::new();
    for n in names {
        if config.stage(n).is_none() {
            return Err(PipelineError::UnknownStage(n.to_string()));
        }
        todo.push(n.to_string());
    }
    while let Some(n) = todo.pop() {
        if set.insert(n.clone()) {
            let decl = config.stage(&n).expect("validated");
            todo.extend(decl.dependencies());
        }
    }
    Ok(set)
}

fn node_id(name: &str) -> String {
    name.replace('-', "_")
}

/// The DAG as a Mermaid flowchart: an edge per dependency, dashed for `after`.
pub fn mermaid(config: &PipelineConfig) -> String {
    let mut s = String::from("flowchart LR\n");
    for st in &config.stages {
        let opt = if st.optional { " (optional)" } else { "" };
        let demand = if st.on_demand { " (on demand)" } else { "" };
        s.push_str(&format!("    {}[\"{}{}{}\"]\n", node_id(&st.name), st.name, opt, demand));
    }
    for st in &config.stages {
        for (dep, data) in edges(st) {
            let arrow = if data { "-->" } else { "-.->" };
            s.push_str(&format!("    {} {arrow} {}\n", node_id(&dep), node_id(&st.name)));
        }
    }
    s
}

/// The DAG in Graphviz DOT.
pub fn dot(config: &PipelineConfig) -> String {
    let mut s = String::from("digraph pipeline {\n    rankdir=LR;\n    node [shape=box];\n");
    for st in &config.stages {
        let style = if st.optional { " style=dashed" } else { "" };
        let demand = if st.on_demand { " (on demand)" } else { "" };
        s.push_str(&format!("    \"{}\" [label=\"{}{demand}\"{style}];\n", st.name, st.name));
    }
    for st in &config.stages {
        for (dep, data) in edges(st) {
            let style = if data { "" } else { " [style=dashed]" };
            s.push_str(&format!("    \"{dep}\" -> \"{}\"{style};\n", st.name));
        }
    }
    s.push_str("}\n");
    s
}

/// (dependency, carries data) for one stage, in declaration order.
fn edges(st: &crate::config::StageDecl) -> Vec<(String, bool)> {
    st.dependencies()
        .into_iter()
        .map(|d| {
            let data = st.inputs.iter().any(|i| matches!(i, Input::Upstream { stage, .. } if *stage == d));
            (d, data)
        })
        .collect()
}
