//! The `appell` command: parses arguments and prints; the work lives in the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
