//! The `appell` command: parses arguments and prints; the work lives in the library.

mod cli;

fn main() -> std::process::ExitCode {
    if let Some(feature) = appell::cpu::missing_feature() {
        appell::cpu::refuse(feature);
        return std::process::ExitCode::from(2);
    }
    cli::main()
}
