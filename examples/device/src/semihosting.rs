//! Semihosting: the firmware's only I/O, the same calls on Arm and RISC-V.
//!
//! A semihosting call puts an operation number and the address of its argument block
//! in the first two argument registers and traps into the debugger — here QEMU
//! (`-semihosting-config enable=on`): `bkpt 0xab` on Armv7-M/Armv8-M, and on RISC-V
//! the sequence `slli x0, x0, 0x1f; ebreak; srai x0, x0, 7` (uncompressed, in one
//! page). Everything else — console, files, command line, exit — is shared. 32-bit
//! conventions on both: `SYS_EXIT` takes its reason code directly.

use core::fmt;

const SYS_OPEN: usize = 0x01;
const SYS_CLOSE: usize = 0x02;
const SYS_WRITE: usize = 0x05;
const SYS_GET_CMDLINE: usize = 0x15;
const SYS_EXIT: usize = 0x18;
/// `SYS_OPEN` mode "wb".
const OPEN_WRITE_TRUNC_BINARY: usize = 5;
/// `ADP_Stopped_ApplicationExit`: QEMU exits with status 0.
const EXIT_SUCCESS: usize = 0x20026;
/// `ADP_Stopped_RunTimeErrorUnknown`: QEMU exits with status 1.
const EXIT_FAILURE: usize = 0x20023;

/// One semihosting call: operation `op` with argument `arg` (an address or a value).
#[cfg(target_arch = "arm")]
fn call(op: usize, arg: usize) -> usize {
    let mut r = op;
    // SAFETY: `bkpt 0xab` is the Arm semihosting trap; QEMU reads r0/r1 and the
    // argument block `arg` points to (owned by the caller across the call), and
    // writes the result to r0. No other state changes.
    #[allow(unsafe_code)]
    unsafe {
        core::arch::asm!("bkpt #0xab", inout("r0") r, in("r1") arg, options(nostack));
    }
    r
}

/// One semihosting call: operation `op` with argument `arg` (an address or a value).
#[cfg(target_arch = "riscv32")]
fn call(op: usize, arg: usize) -> usize {
    let mut r = op;
    // SAFETY: the three-instruction sequence is the RISC-V semihosting trap; QEMU reads
    // a0/a1 and the argument block `arg` points to, and writes the result to a0.
    #[allow(unsafe_code)]
    unsafe {
        core::arch::asm!(
            ".balign 16",
            ".option push",
            ".option norvc",
            "slli x0, x0, 0x1f",
            "ebreak",
            "srai x0, x0, 7",
            ".option pop",
            inout("a0") r,
            in("a1") arg,
            options(nostack)
        );
    }
    r
}

/// The host's console (QEMU's standard output, the file `:tt` opened for writing,
/// as cortex-m-semihosting does; `SYS_WRITE0` would go to QEMU's standard error).
pub struct Console;

impl Console {
    /// Writes `bytes` to the console.
    pub fn write(&mut self, bytes: &[u8]) -> Result<(), &'static str> {
        /// `SYS_OPEN` mode "w": `:tt` in that mode is standard output.
        const OPEN_WRITE: usize = 4;
        let tt = b":tt\0";
        let block = [tt.as_ptr() as usize, OPEN_WRITE, tt.len() - 1];
        let handle = call(SYS_OPEN, block.as_ptr() as usize);
        if handle as isize == -1 {
            return Err("SYS_OPEN");
        }
        let mut file = HostFile { handle };
        let written = file.write(bytes);
        let closed = file.close();
        written.and(closed)
    }
}

/// For `write!` ([`hprintln!`]), where a value has only a `Display`.
impl fmt::Write for Console {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        self.write(s.as_bytes()).map_err(|_| fmt::Error)
    }
}

/// One piece of a console line (see [`say`]).
#[derive(Clone, Copy)]
pub enum Part<'a> {
    /// Text as it is.
    Text(&'a str),
    /// A number in decimal.
    Dec(u32),
    /// A number as eight hexadecimal digits (lower case, zero-padded).
    Hex(u32),
}

/// Writes `parts` to the console, numbers converted here: `core::fmt` (`fmt::write`,
/// the padding of `Formatter`, `Display` and `LowerHex` for `u32`) would cost Fig. 6's
/// firmware 1.2 KiB of flash, the price of every `u32` printed through `{}`.
pub fn say(parts: &[Part]) {
    for part in parts {
        let mut buf = [0u8; 10];
        let bytes = match *part {
            Part::Text(s) => s.as_bytes(),
            Part::Dec(n) => digits(n, 10, 1, &mut buf),
            Part::Hex(n) => digits(n, 16, 8, &mut buf),
        };
        let _ = Console.write(bytes);
    }
}

/// `n` in base `radix` (at most 16), with at least `width` digits (at most 10):
/// the tail of `buf`.
fn digits(mut n: u32, radix: u32, width: usize, buf: &mut [u8; 10]) -> &[u8] {
    let mut start = buf.len();
    while start > 0 && (n > 0 || start + width > buf.len()) {
        start -= 1;
        buf[start] = b"0123456789abcdef"[(n % radix) as usize];
        n /= radix;
    }
    &buf[start..]
}

/// `println!` onto the host's console, for values with only a `Display` (the error
/// estimate's figure); numbers and text go through [`say`].
#[macro_export]
macro_rules! hprintln {
    ($($arg:tt)*) => {{
        use core::fmt::Write as _;
        let _ = writeln!($crate::semihosting::Console, $($arg)*);
    }};
}

/// Ends the run: QEMU exits with 0 (`ok`) or 1.
pub fn exit(ok: bool) -> ! {
    call(SYS_EXIT, if ok { EXIT_SUCCESS } else { EXIT_FAILURE });
    #[allow(clippy::empty_loop)]
    loop {}
}

/// A file on the host, written front to back.
pub struct HostFile {
    handle: usize,
}

impl HostFile {
    /// Creates (truncates) `path` (NUL-terminated) on the host.
    pub fn create(path: &[u8]) -> Result<Self, &'static str> {
        debug_assert_eq!(path.last(), Some(&0));
        let block = [
            path.as_ptr() as usize,
            OPEN_WRITE_TRUNC_BINARY,
            path.len() - 1,
        ];
        let handle = call(SYS_OPEN, block.as_ptr() as usize);
        if handle as isize == -1 {
            return Err("SYS_OPEN");
        }
        Ok(Self { handle })
    }

    /// Appends `bytes`.
    pub fn write(&mut self, bytes: &[u8]) -> Result<(), &'static str> {
        let block = [self.handle, bytes.as_ptr() as usize, bytes.len()];
        match call(SYS_WRITE, block.as_ptr() as usize) {
            0 => Ok(()),
            _ => Err("SYS_WRITE"),
        }
    }

    /// Closes the file.
    pub fn close(self) -> Result<(), &'static str> {
        let block = [self.handle];
        match call(SYS_CLOSE, block.as_ptr() as usize) {
            0 => Ok(()),
            _ => Err("SYS_CLOSE"),
        }
    }
}

/// The second word of the semihosting command line (`PROGRAM PATH`), NUL-terminated
/// in `buf`, or `default` (without its NUL) when there is none.
pub fn output_path<'b>(buf: &'b mut [u8; 256], default: &[u8]) -> &'b [u8] {
    let mut line = [0u8; 256];
    let mut block = [line.as_mut_ptr() as usize, line.len()];
    // The call writes the line into `line` and its length into `block[1]`.
    let ok = call(SYS_GET_CMDLINE, block.as_mut_ptr() as usize) == 0;
    let line = if ok {
        &line[..block[1].min(line.len())]
    } else {
        &[][..]
    };
    let path = line
        .split(|&b| b == b' ' || b == 0)
        .filter(|w| !w.is_empty())
        .nth(1)
        .unwrap_or(default);
    let n = path.len().min(255);
    buf[..n].copy_from_slice(&path[..n]);
    buf[n] = 0;
    &buf[..n + 1]
}
