//! `chisel` — the command line of bevy_chisel's kernels.
//!
//! `chisel budget` prints the exact kernel's bit budget: the admissible
//! input range and the width of every derived quantity.

use clap::{Parser, Subcommand};

mod budget;

/// Exact solid modelling kernels of bevy_chisel, from the command line.
#[derive(Parser)]
#[command(name = "chisel", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the exact kernel's bit budget (input range and derived widths).
    Budget {
        /// One line of JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() {
    let cli = Cli::parse();
    match cli.command {
        Command::Budget { json } => budget::print(json),
    }
}
