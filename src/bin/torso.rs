//! The `torso` command-line tool; see `torso --help`.

fn main() {
    std::process::exit(breathing_torso::cli::main());
}
