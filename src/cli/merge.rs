//! `hexsim merge`: the results of a batch's shards joined into one file.

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct MergeArgs {
    /// The shards' results files.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// The merged results file.
    #[arg(short, long, default_value = "results.jsonl")]
    output: PathBuf,
}

pub fn merge(args: MergeArgs) -> Result<()> {
    use hexsim::batch::{self, results};
    // the merged file must not replace a shard it is made from
    hexsim::record::output::check_distinct(
        [("--output", args.output.as_path())],
        args.shards.iter().map(|p| ("shard", p.as_path())),
    )?;
    let mut parts = Vec::new();
    for path in &args.shards {
        let (records, _) = results::read(path, false)?;
        parts.push((path.clone(), records));
    }
    let merged = batch::merge(&parts)?;
    results::write_all(&args.output, &merged)?;
    out!(
        "merged {} results from {} file(s) into {}",
        merged.len(),
        parts.len(),
        args.output.display()
    );
    Ok(())
}
