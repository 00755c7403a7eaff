//! Picks the linker script for the target: cortex-m-rt's `link.x` with the board's
//! `memory.x` on Arm (MPS2 boards, or the AN505's secure aliases for Armv8-M), the
//! firmware's own `riscv-virt.x` on RISC-V.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let target = env::var("TARGET").expect("TARGET");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-env=CAUSTIC_FIRMWARE_TARGET={target}");
    println!("cargo:rerun-if-changed=memory");
    println!("cargo:rerun-if-changed=build.rs");
    if target.starts_with("riscv32") {
        fs::copy("memory/riscv-virt.x", out.join("riscv-virt.x")).expect("copy riscv-virt.x");
        println!("cargo:rustc-link-arg=-Triscv-virt.x");
    } else {
        let memory = if target.starts_with("thumbv8m") {
            "memory/an505.x"
        } else {
            "memory/mps2.x"
        };
        fs::copy(memory, out.join("memory.x")).expect("copy memory.x");
        println!("cargo:rustc-link-arg=-Tlink.x");
    }
}
