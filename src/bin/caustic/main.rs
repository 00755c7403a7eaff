//! `caustic`: render a scene file to PNG, PFM or OpenEXR, or compare two images.
//!
//! `caustic --help`, `caustic render --help` and `caustic compare --help` list every
//! flag with its default; `caustic completions bash|zsh|fish` prints a completion
//! script. Exit status: 0 on success, 2 on bad input (flags, scene, files), 1 when
//! writing the result fails after the render.

mod compare;
mod render;

use std::process::ExitCode;

use caustic::desktop::cli::{CompareArgs, RenderArgs};
use clap::{CommandFactory, Parser, Subcommand};

/// A photon-mapping renderer for the caustics of glass and mirrors.
#[derive(Parser, Debug)]
#[command(
    name = "caustic",
    version,
    propagate_version = true,
    arg_required_else_help = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene file to an image (PNG, PFM or OpenEXR by extension)
    #[command(allow_negative_numbers = true)]
    Render(Box<RenderArgs>),
    /// Compare an image with a reference: relative RMSE and mean absolute error as JSON
    Compare(CompareArgs),
    /// Print a shell completion script (e.g. `caustic completions bash > caustic.bash`)
    Completions {
        /// The shell
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

/// A failure and its exit status.
pub struct Failure {
    code: u8,
    message: String,
}

/// Bad input: exit status 2.
pub fn bad_input(message: impl Into<String>) -> Failure {
    Failure {
        code: 2,
        message: message.into(),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Completions { shell } => {
            clap_complete::generate(
                shell,
                &mut Cli::command(),
                "caustic",
                &mut std::io::stdout(),
            );
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("caustic: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}
