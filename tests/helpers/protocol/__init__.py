"""Protocol-core helpers: Hypothesis strategies, the document's vectors, a sample of every
catalogue parameter, the boundary tables' naming, what a real Z-1Pro sends."""
