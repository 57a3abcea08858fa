//! The `whitted` binary: checks the CPU, calls [`whitted::cli::run`], maps errors to exit code 2;
//! its allocator asks for huge pages on big blocks ([`whitted::hugepages`]).

use std::process::ExitCode;

/// Big blocks (the BVH, leaf blocks, SoA arrays, queues) on transparent huge pages where Linux
/// offers them on request (`whitted::hugepages`).
#[global_allocator]
static ALLOCATOR: whitted::hugepages::HugePages = whitted::hugepages::HugePages;

fn main() -> ExitCode {
    whitted::hugepages::keep_freed_memory();
    if !whitted::cpu_supported() {
        eprintln!(
            "error: this build of whitted needs a CPU with AVX2 and FMA (x86-64-v3); \
             rebuild without `-C target-cpu=x86-64-v3` in .cargo/config.toml to run here"
        );
        return ExitCode::from(2);
    }
    match whitted::cli::run(std::env::args_os().collect()) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`whitted bench | head`): nothing left to say, like `cat`.
        Err(whitted::Error::Io { source, .. })
            if source.kind() == std::io::ErrorKind::BrokenPipe =>
        {
            ExitCode::SUCCESS
        }
        Err(err) => {
            eprintln!("error: {err}");
            ExitCode::from(2)
        }
    }
}
