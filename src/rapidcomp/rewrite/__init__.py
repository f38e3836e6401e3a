"""Writing compensated values back into RAPID text: numbers, names, edits."""
