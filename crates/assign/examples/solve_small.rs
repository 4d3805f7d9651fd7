//! Solves a small assignment problem with each of the three solvers: a square matrix, a
//! rectangular one, a maximisation, and a matching with a rejection threshold.
//!
//! Run: `cargo run --example solve_small`

use assign::{solve, solve_with_threshold, Method, Options};

fn main() -> Result<(), assign::AssignError> {
    // Row-major 3 x 3: three workers (rows), three jobs (columns).
    let cost = [
        4.0, 1.0, 3.0, //
        2.0, 0.0, 5.0, //
        3.0, 2.0, 2.0,
    ];
    for method in [
        Method::JonkerVolgenant,
        Method::Hungarian,
        Method::NetworkSimplex,
    ] {
        let a = solve(
            &cost,
            3,
            3,
            &Options {
                method,
                maximize: false,
            },
        )?;
        println!("{method:?}: pairs {:?}, total cost {}", a.pairs(), a.cost);
    }

    // Rectangular (2 x 4): every row is assigned, two columns stay free.
    let wide = [
        7.0, 2.0, 9.0, 4.0, //
        3.0, 8.0, 1.0, 6.0,
    ];
    let a = solve(&wide, 2, 4, &Options::default())?;
    println!("2 x 4: pairs {:?}, cost {}", a.pairs(), a.cost);

    let a = solve(
        &cost,
        3,
        3,
        &Options {
            maximize: true,
            ..Options::default()
        },
    )?;
    println!("maximised: pairs {:?}, total {}", a.pairs(), a.cost);

    // Keep only pairs cheaper than 1.5: rows and columns may stay unassigned.
    let t = solve_with_threshold(&cost, 3, 3, 1.5, &Options::default())?;
    println!("threshold 1.5: rows -> columns {:?}", t.row_to_col);
    Ok(())
}
