//! The `radray` binary: parse the command line, run it, print the error chain, exit with its code
//! (0 success, 2 bad input or usage, 1 internal error).

use clap::Parser;

fn main() {
    let cli = match radray::cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            std::process::exit(code);
        }
    };
    // A panic is a bug in radray, never the user's fault: report it as an internal error (exit 1).
    match std::panic::catch_unwind(|| radray::cli::run(cli)) {
        Ok(Ok(())) => {}
        Ok(Err(failure)) => {
            eprintln!("error: {failure}");
            std::process::exit(failure.exit_code);
        }
        Err(_) => {
            eprintln!("error: internal error (a bug in radray); please report it with the command that caused it");
            std::process::exit(1);
        }
    }
}
