//! Raw bindings to Intel Embree.
