//! The `allanscope` binary: logging to standard error, the command line, exit statuses.
#![forbid(unsafe_code)]

mod cli;

fn main() {
    tracing_subscriber::fmt()
        // Log lines above a live run's status line (cli/status.rs), never through it.
        .with_writer(cli::LogWriter)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_env("ALLANSCOPE_LOG")
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .init();
    if let Err(e) = cli::main_with_args(std::env::args_os()) {
        eprintln!("allanscope: {e:#}");
        std::process::exit(allanscope::error::exit_status(&e));
    }
}
