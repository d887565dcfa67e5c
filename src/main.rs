//! The `trajdrift` binary: the command line of the library's [`trajdrift::cli`], nothing else.

fn main() -> std::process::ExitCode {
    trajdrift::cli::allocator::return_large_blocks();
    std::process::ExitCode::from(trajdrift::cli::main_with_args(
        std::env::args_os().collect(),
    ))
}
