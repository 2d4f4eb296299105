"""The page layer: the report's HTML (sections, tables, numbers with their data-key), its figures
(matplotlib, drawn in forked children), its units on the page, the run table as CSV; from what the
reading and judging layers return."""
