//! The `torso` command-line tool: one file per subcommand.

pub mod mesh;

use clap::{Parser, Subcommand};

/// Breathing torso simulator: simulate, fit SLP recordings, validate against spirometry.
#[derive(Parser, Debug)]
#[command(name = "torso", version, about)]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands of `torso`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print the library version.
    Version,
    /// Prepare, inspect and volume-mesh subject surfaces.
    Mesh {
        /// The mesh subcommand.
        #[command(subcommand)]
        command: mesh::MeshCommand,
    },
}

/// Entry point: parses arguments, runs the subcommand, returns the process exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    let result: crate::Result<()> = match cli.command {
        Command::Version => {
            println!("torso {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        Command::Mesh { command } => mesh::run(command),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
