//! `raykin`: path-trace animated glTF scenes. With no arguments it opens the viewer on the embedded default
//! scene when a display is present, else renders that scene to out/default.png.

mod adapter;
mod bench;
mod cli;
mod messages;
mod outputs;
mod provenance;
mod record_cmd;
mod render_cmd;
mod scenes;
mod stats;
mod view;

use clap::Parser;

fn main() -> std::process::ExitCode {
    messages::ensure_runtime_dir();
    messages::init();
    let cli = cli::Cli::parse();
    let result = match cli.command {
        Some(cli::Command::Render(args)) => render_cmd::run(&args),
        // The recorder has its own exit statuses (interrupted: 130).
        Some(cli::Command::Record(args)) => return record_cmd::main(&args),
        Some(cli::Command::Bench(args)) => bench::run(&args),
        Some(cli::Command::View(args)) => view::run(&args),
        None if view::display_present() => view::run_default(),
        None => render_cmd::run_default(),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("raykin: error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
