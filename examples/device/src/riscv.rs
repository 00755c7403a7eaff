//! RISC-V (RV32IMAC on QEMU `virt`): the reset code, with no runtime crate. `_start`
//! sets the global and stack pointers, paints the stack (for the high-water mark),
//! clears `.bss` and calls [`crate::run`]; a trap ends the run with a failure.

/// The value the stack is painted with (cortex-m-rt's, so both read alike).
pub const STACK_PAINT: u32 = 0xCCCC_CCCC;

core::arch::global_asm!(
    ".section .text.start, \"ax\"",
    ".global _start",
    "_start:",
    ".option push",
    ".option norelax",
    "la gp, __global_pointer$",
    ".option pop",
    "la t0, trap",
    "csrw mtvec, t0",
    // Paint the stack.
    "la t0, _stack_end",
    "la t1, _stack_start",
    "li t2, 0xCCCCCCCC",
    "1: bgeu t0, t1, 2f",
    "sw t2, 0(t0)",
    "addi t0, t0, 4",
    "j 1b",
    // Clear .bss.
    "2: la t0, _sbss",
    "la t1, _ebss",
    "3: bgeu t0, t1, 4f",
    "sw zero, 0(t0)",
    "addi t0, t0, 4",
    "j 3b",
    "4: la sp, _stack_start",
    "call caustic_riscv_main",
    "5: j 5b",
    ".balign 4",
    "trap: call caustic_riscv_trap",
    "6: j 6b",
);

#[no_mangle]
extern "C" fn caustic_riscv_main() -> ! {
    crate::run()
}

#[no_mangle]
extern "C" fn caustic_riscv_trap() -> ! {
    let (cause, pc): (usize, usize);
    // SAFETY: reading two machine-mode CSRs has no side effect.
    #[allow(unsafe_code)]
    unsafe {
        core::arch::asm!("csrr {0}, mcause", "csrr {1}, mepc", out(reg) cause, out(reg) pc);
    }
    use crate::semihosting::Part::{Hex, Text};
    crate::semihosting::say(&[
        Text("TRAP mcause=0x"),
        Hex(cause as u32),
        Text(" mepc=0x"),
        Hex(pc as u32),
        Text("\n"),
    ]);
    crate::semihosting::exit(false)
}
