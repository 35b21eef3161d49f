"""The core every layer above shares: the Problem protocol and its evaluation, declared
capabilities, run records, batching, requirements, run views, statistics, Pareto fronts,
the case-variation draws, plotting style and process-level performance settings."""
