//! Touchstone files (v1 `.sNp` and v2) as a VNA, an EM solver or scikit-rf writes them.
//!
//! Takes the bytes of a file and its path (the extension `.sNp` gives the port count of a v1
//! file; a v2 file gives it with `[Number of Ports]`). Gives a [`Network`]: the frequency grid
//! in Hz, the full S matrix per frequency, the reference impedance per frequency and port
//! (complex), and notes on what was recognised and skipped. [`Network::param`] picks one
//! S-parameter ([`SParam`], e.g. S21) for the energy stage.
//!
//! What is read (scikit-rf 2.2's `skrf.io.touchstone` is the reference reader; the fixtures
//! in `data/touchstone/` were written by it, `scripts/make_skrf_fixture.py`):
//! * text: a UTF-8 byte-order mark is dropped; a file that is not UTF-8 is read as Latin-1
//!   (vendor comments with `°`); lines end in LF, CRLF or CR;
//! * `!` comments, whole-line or trailing; the option line `# <Hz|kHz|MHz|GHz> S <RI|MA|DB>
//!   R <z0 …>` (first one wins, defaults `GHz S MA R 50`); `R` takes one value or one per
//!   port, real or complex (`(10+10j)`, as scikit-rf writes it);
//! * data: a point is `f` and 2·n² numbers (n(n+1) for a v2 `[Matrix Format] Lower|Upper`),
//!   wrapped over as many lines as the writer likes, each point starting a line. Two-port
//!   points are S11 S21 S12 S22 (v1, and v2 `[Two-Port Data Order] 21_12`) or S11 S12 S21
//!   S22 (`12_21`); other port counts are row-major. RI as given; MA is |S|·e^{jθ}, DB is
//!   10^(a/20)·e^{jθ} with θ in degrees (θ·π/180, as scikit-rf), and `-inf` dB (scikit-rf
//!   writes it for |S| = 0) is 0;
//! * v2 keywords `[Version]`, `[Number of Ports]`, `[Two-Port Data Order]`, `[Number of
//!   Frequencies]` (checked), `[Number of Noise Frequencies]`, `[Reference]` (one value per
//!   port, may continue on the next lines), `[Matrix Format]`, `[Begin Information]` …
//!   `[End Information]` (skipped), `[Network Data]`, `[Noise Data]`, `[End]`;
//! * noise parameters: a v2 `[Noise Data]` block, or in a v1 two-port file the rows after
//!   the frequency first falls, are recognised, skipped and noted;
//! * HFSS exports: `! Port Impedance re im …` after each point (one complex value per port,
//!   or the full matrix whose diagonal is taken, continued on `!` lines of numbers) set the
//!   reference impedance of that point, as scikit-rf does.
//!
//! What is refused, in one line naming the file, the line and the reason: a parameter type
//! other than S (Y, Z, G, H), mixed-mode data, an unknown keyword or option, a token that is
//! not a number, NaN or ±inf (other than a dB magnitude of −inf), a |S| above [`MAX_VALUE`]
//! (1e100, or 2000 dB: its energy would overflow), a point that does not start
//! a line or ends inside one, or a continuation line with an odd count of numbers (the port
//! count does not fit the data: points start with f, continuation lines hold pairs; this is
//! what tells one-port data named `.s2p` from two-port data), a frequency that does
//! not increase (naming the line where it stops and the line before; in a v1 two-port file
//! only a falling row of five numbers starts the noise parameters), a v2 two-port file
//! without `[Two-Port Data Order]` (v2.0 requires it: which pair is S21 is otherwise
//! unknown), a truncated last point, a v1 file without an `.sNp` name, and a port count
//! of the name that disagrees with `[Number of Ports]`.
//!
//! Why not the `touchstone` crate (0.17, evaluated): it parses into its own network type
//! with an allocation per row and reports errors without file line numbers; the energy stage
//! reads tens of thousands of files and must name the file and line of a bad number, so a
//! small dedicated reader is both faster and gives the errors users need.
//!
//! The module's parts: [`network`] (the parsed [`Network`], [`SParam`], [`TsFormat`], text
//! decoding and the bounds [`MAX_PORTS`], [`MAX_VALUE`]), [`reader`] ([`parse_touchstone`],
//! [`read_touchstone`]) and [`writer`] ([`write_s2p`]). Every item is re-exported here.
//! The reader's lines, tokens and numbers are in `text` (private).

pub mod network;
pub mod reader;
mod text;
pub mod writer;

pub use network::{decode, ports_from_name, Network, SParam, TsFormat, MAX_PORTS, MAX_VALUE};
pub use reader::{parse_touchstone, read_touchstone};
pub use writer::write_s2p;
