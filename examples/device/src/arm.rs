//! Arm (Cortex-M3/M4F/M33): cortex-m-rt's reset handler (which paints the stack) calls
//! [`crate::run`]; faults end the run with a failure.

use cortex_m_rt::{entry, exception, ExceptionFrame};

/// The value cortex-m-rt paints the stack with.
pub const STACK_PAINT: u32 = cortex_m_rt::STACK_PAINT_VALUE;

#[entry]
fn main() -> ! {
    crate::run()
}

#[exception]
#[allow(unsafe_code)]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    use crate::semihosting::Part::{Hex, Text};
    crate::semihosting::say(&[Text("HARDFAULT pc=0x"), Hex(frame.pc()), Text("\n")]);
    crate::semihosting::exit(false)
}
