fn main() -> std::process::ExitCode {
    plc_conformance::cli::main()
}
