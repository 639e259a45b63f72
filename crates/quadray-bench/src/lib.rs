//! quadray's benchmark and demo harness: the paper tables and figures of each technique as
//! functions returning rows, the demo pictures, and the tables and plots they write. It uses the
//! technique crates only through their public APIs, as any other program would.

pub mod displace;
pub mod indirect;
pub mod report;
pub mod shadows;
