"""One-off studies, kept apart from the library code: they use the models and
the replay, nothing imports them."""
