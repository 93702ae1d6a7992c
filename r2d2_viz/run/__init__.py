"""The ways a run ends, each in a module of its own (export to a dataset, render to a video, compare runs…).

At the top of the house with runner and cli: a run kind may import every stage; the CLI picks one."""
