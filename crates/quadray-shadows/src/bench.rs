//! The paper's tables and figure 6 (filled in below).
