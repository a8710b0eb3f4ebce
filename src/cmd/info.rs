//! `raykit info`: the names the other commands accept.

use anyhow::Result;
use clap::{Args, ValueEnum};
use raykit_core::accel::AccelKind;
use raykit_core::tri::TestKind;
use std::process::ExitCode;

/// What to list.
#[derive(Clone, Copy, ValueEnum)]
pub enum Topic {
    /// Acceleration structures (--accel).
    Accels,
    /// Ray/triangle tests (--test).
    Tests,
    /// Built-in scenes (--scene builtin:NAME, --mesh builtin:NAME).
    Scenes,
}

/// Arguments of `raykit info`.
#[derive(Args)]
pub struct InfoArgs {
    /// What to list.
    topic: Topic,
}

/// Print the list.
pub fn run(args: InfoArgs) -> Result<ExitCode> {
    match args.topic {
        Topic::Accels => {
            for k in AccelKind::ALL {
                println!("{:<14} {}", k.name(), k.description());
            }
        }
        Topic::Tests => {
            for k in TestKind::ALL {
                println!("{:<14} {}", k.name(), k.description());
            }
        }
        Topic::Scenes => {
            for info in raykit_scene::BUILTINS {
                println!(
                    "builtin:{:<10} {} (keys: {})",
                    info.name,
                    info.description,
                    info.keys.join(", ")
                );
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
