//! `raykin`: path-trace animated glTF scenes. With no arguments it renders the embedded default scene.

mod bench;
mod cli;
mod render_cmd;

use clap::Parser;

fn main() -> std::process::ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = cli::Cli::parse();
    let result = match cli.command {
        Some(cli::Command::Render(args)) => render_cmd::run(&args),
        Some(cli::Command::Bench(args)) => bench::run(&args),
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
