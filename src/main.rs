//! The `studyrun` command: see `studyrun --help`.

mod cli;
mod interrupt;

fn main() -> std::process::ExitCode {
    // A closed pipe (`studyrun --dry-run grid.yaml | head`) ends the command quietly,
    // as it does every other Unix tool, instead of a panic in `println!`.
    // SAFETY: restoring the default action of one signal before any thread starts.
    unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    cli::main()
}
