"""Post-processing of vibrofeed H5MD results: transport, flights, singulation."""
