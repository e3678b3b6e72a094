//! Stage `confusion`: hidden-effect campaigns from the virtual rig (seeded
//! draws of every class, including one effect outside the vocabulary),
//! diagnosed blind by rig_diagnose::diagnose_campaign: confusion matrix,
//! parameter errors and confusion.md.

use crate::StageCtx;
use anyhow::{Result, bail};
use rig_diagnose::{DiagnoseOptions, diagnose_campaign};
use rig_virtual_rig::Protocol;
use rig_virtual_rig::confusion::{confusion_table, params_table, run_confusion, tolerance};
use std::fmt::Write as _;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let draws = ctx.param_usize("draws_per_class")?;
    let seed = ctx.param_usize("seed")? as u64;
    let protocol = match ctx.param_str("protocol")?.as_str() {
        "small" => Protocol::small(),
        "full" => Protocol::full(),
        other => bail!("pipeline.toml: stage {}: protocol = {other:?} must be \"small\" or \"full\"", ctx.name),
    };
    // The diagnosis stage's options as it ran them (pipeline.toml is their one home).
    // The thesis values are not needed for a verdict; without them no baseline
    // is estimated for the free-run comparison, which keeps this stage fast.
    let opts: DiagnoseOptions = ctx.read_json("data/diagnose-options.json")?;
    let out = run_confusion(draws, &protocol, seed, |c| {
        let d = diagnose_campaign(c, None, &opts).map_err(|e| e.to_string())?;
        Ok((d.verdict.clone(), d.findings.first().map(|f| f.params.clone()).unwrap_or_default()))
    });
    let matrix = confusion_table(&out);
    let params = params_table(&out);
    ctx.write_table("tables/confusion-matrix.csv", &matrix)?;
    ctx.write_table("tables/confusion-params.csv", &params)?;

    let correct = out.iter().filter(|o| o.correct()).count();
    let mut md = String::new();
    let _ = writeln!(md, "# Hidden-effect confusion matrix\n");
    let _ = writeln!(
        md,
        "{} virtual-rig campaigns ({} per class, protocol `{}`: {} operating points of {} s, seeds from {}), each \
         diagnosed blind (calibrate → diagnose) after the effect was hidden in the truth model. Motor cogging is \
         outside the vocabulary: the right answer is `unexplained`. {} of {} verdicts are right.\n",
        out.len(),
        draws,
        ctx.param_str("protocol")?,
        protocol.op_points.len(),
        protocol.op_duration_s,
        seed,
        correct,
        out.len()
    );
    let _ = writeln!(md, "| hidden | expected | {} | accuracy |", rig_virtual_rig::confusion::VERDICTS.join(" | "));
    let _ = writeln!(md, "|{}", "---|".repeat(rig_virtual_rig::confusion::VERDICTS.len() + 3));
    for r in &matrix.rows {
        let _ = writeln!(md, "| {} |", r.join(" | "));
    }
    let _ = writeln!(md, "\n## Parameter errors of the right verdicts (tables/confusion-params.csv)\n");
    let _ = writeln!(
        md,
        "| hidden | seed | parameter | truth | estimate | relative error | tolerance | within |\n|---|---|---|---|---|---|---|---|"
    );
    for r in &params.rows {
        let tol = tolerance(&r[2]);
        let err: f64 = r[5].parse().unwrap_or(f64::NAN);
        let truth: f64 = r[3].parse().unwrap_or(f64::NAN);
        let within = if r[2] == "frequency_hz" { (err * truth).abs() <= tol } else { err.abs() <= tol };
        let _ =
            writeln!(md, "| {} | {} | {} | {} | {} | {} | {} | {} |", r[0], r[1], r[2], r[3], r[4], r[5], tol, within);
    }
    let _ = writeln!(md, "\nTolerance: relative error, except `frequency_hz` (absolute, Hz) and `order` (exact).");
    let wrong: Vec<_> = out.iter().filter(|o| !o.correct()).collect();
    if !wrong.is_empty() {
        let _ = writeln!(md, "\n## Wrong verdicts\n");
        for o in wrong {
            let _ = writeln!(md, "- {} seed {}: {:?} → `{}`", o.class, o.seed, o.hidden, o.verdict());
        }
    }
    ctx.write_text("confusion.md", &md)?;
    Ok(())
}
