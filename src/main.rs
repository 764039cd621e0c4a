//! The `studyrun` command: see `studyrun --help`.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
