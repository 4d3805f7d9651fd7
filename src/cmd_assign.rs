//! `pedomatch assign`: solve a linear assignment problem read from a CSV cost matrix.

use crate::option_args::{help, word};
use crate::output;
use crate::CliError;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct AssignArgs {
    /// CSV file of costs: one matrix row per line, `inf` marks a forbidden pair.
    pub cost: PathBuf,
    #[arg(long, alias = "method", value_parser = word::<assign::Method>(), help = help("solver"))]
    pub solver: Option<assign::Method>,
    /// Maximise the total instead of minimising it.
    #[arg(long)]
    pub maximize: bool,
    /// Print the solution as one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: AssignArgs) -> Result<(), CliError> {
    let (cost, rows, cols) = output::read_cost_csv(&args.cost)?;
    let options = assign::Options {
        method: args.solver.unwrap_or_default(),
        maximize: args.maximize,
    };
    let result = assign::solve(&cost, rows, cols, &options)
        .map_err(|e| format!("{}: {e}", args.cost.display()))?;
    let pairs: Vec<(usize, usize)> = result
        .row_to_col
        .iter()
        .enumerate()
        .filter_map(|(i, j)| j.map(|j| (i, j)))
        .collect();
    if args.json {
        let value = serde_json::json!({
            "rows": rows,
            "cols": cols,
            "solver": args.solver.unwrap_or_default().to_string(),
            "maximize": args.maximize,
            "pairs": pairs,
            "total_cost": result.cost,
        });
        outln!(
            "{}",
            serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?
        );
    } else {
        outln!("row\tcol\tcost");
        for &(i, j) in &pairs {
            outln!("{i}\t{j}\t{}", cost[i * cols + j]);
        }
        outln!("total cost: {} ({} pairs)", result.cost, pairs.len());
    }
    Ok(())
}
