"""The numeric side: the guaranteed estimators, their proofs, the workflows and the `garant` command."""
