//! Motion graphs: synthesis by randomized search over a hierarchy of motion graphs (Arikan and Forsyth 2002).
