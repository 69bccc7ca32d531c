//! oit-lab: the command line. See `oit-lab --help`.

//! Every command's work is in the library (`oit_lab::study::run::run_command`, ...); the
//! options are read in `cli.rs`; this file dispatches.

mod cli;

use cli::{Args, Fail};
use std::process::ExitCode;

/// The commands; anything else is the main job's options (`oit-lab [run] [OPTIONS]`).
const COMMANDS: [&str; 9] = [
    "run",
    "evaluate",
    "dump",
    "bench",
    "faint",
    "scenes",
    "stability",
    "peers",
    "help",
];

fn main() -> ExitCode {
    let mut rest: Vec<String> = std::env::args().skip(1).collect();
    let cmd = match rest.first() {
        Some(c) if COMMANDS.contains(&c.as_str()) => rest.remove(0),
        _ => "run".to_string(),
    };
    let mut args = Args { rest };
    let result = if cmd == "help" {
        print!("{}", cli::HELP);
        Ok(())
    } else if args.flag(&["-h", "--help"]) {
        print!("{}", cli::help_of(&cmd));
        Ok(())
    } else {
        match cmd.as_str() {
            "scenes" => cli::cmd_scenes(args),
            "stability" => cli::cmd_stability(args),
            "peers" => cli::cmd_peers(args),
            "bench" => cli::cmd_bench(args),
            "faint" => cli::cmd_faint(args),
            "evaluate" => cli::cmd_evaluate(args),
            "dump" => cli::cmd_dump(args),
            _ => cli::cmd_run(args),
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Fail(m, show_usage)) => {
            eprintln!("error: {m}");
            if show_usage {
                eprintln!("(see oit-lab --help)");
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}
