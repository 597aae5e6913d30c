//! A shaded preview picture of a field: a heightmap along the view axis found by interval
//! pruning, shaded from the gradient.
