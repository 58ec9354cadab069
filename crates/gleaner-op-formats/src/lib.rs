//! OP formats. TODO
