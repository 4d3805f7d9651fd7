//! `pedomatch assign`: solve a linear assignment problem read from a CSV cost matrix.

use crate::output;
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum SolverArg {
    Jv,
    Hungarian,
    Simplex,
}

impl From<SolverArg> for assign::Method {
    fn from(s: SolverArg) -> Self {
        match s {
            SolverArg::Jv => assign::Method::JonkerVolgenant,
            SolverArg::Hungarian => assign::Method::Hungarian,
            SolverArg::Simplex => assign::Method::NetworkSimplex,
        }
    }
}

#[derive(Args)]
pub struct AssignArgs {
    /// CSV file of costs: one matrix row per line, `inf` marks a forbidden pair.
    pub cost: PathBuf,
    /// Which solver to use.
    #[arg(long, value_enum, default_value = "jv")]
    pub method: SolverArg,
    /// Maximise the total instead of minimising it.
    #[arg(long)]
    pub maximize: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: AssignArgs) -> Result<(), String> {
    let (cost, rows, cols) = output::read_cost_csv(&args.cost)?;
    let options = assign::Options {
        method: args.method.into(),
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
            "method": format!("{:?}", args.method).to_lowercase(),
            "maximize": args.maximize,
            "pairs": pairs,
            "total_cost": result.cost,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?
        );
    } else {
        println!("row\tcol\tcost");
        for &(i, j) in &pairs {
            println!("{i}\t{j}\t{}", cost[i * cols + j]);
        }
        println!("total cost: {} ({} pairs)", result.cost, pairs.len());
    }
    Ok(())
}
