"""Writes every option of evo's evo_ape, evo_rpe, evo_res and evo_traj argument parsers as a TSV.

Run with the evo whose flags trajdrift must accept (1.38.1):
    python tests/python/extract_evo_flags.py > tests/data/evo-1.38.1-flags.tsv
The parsers are evo's own (evo.cli.<tool>_parser.parser()), walked through argparse's actions, so the
list is what evo itself accepts. Columns: tool, subcommand (form), option strings (comma separated),
number of values (0 = a switch), the first choice or an example value.
"""

import argparse
import importlib

import evo

EXAMPLES = {
    int: "3",
    float: "0.5",
}


def example(action):
    if action.choices:
        return str(list(action.choices)[0])
    if action.type in EXAMPLES:
        return EXAMPLES[action.type]
    return "X"


def main():
    print(f"# evo {evo.__version__}: options of the evo_ape/evo_rpe/evo_res/evo_traj argument parsers")
    print("# tool\tsubcommand\toptions\tnargs\texample")
    for tool in ("ape", "rpe", "res", "traj"):
        parser = importlib.import_module(f"evo.cli.{tool}_parser").parser()
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        forms = list(subs[0].choices.items()) if subs else [("-", parser)]
        for form, sub in forms:
            for a in sub._actions:
                if not a.option_strings or isinstance(a, argparse._HelpAction):
                    continue
                if a.nargs == 0:
                    n = 0
                elif isinstance(a.nargs, int):
                    n = a.nargs
                else:
                    n = 1
                print(f"{tool}\t{form}\t{','.join(a.option_strings)}\t{n}\t{example(a)}")


if __name__ == "__main__":
    main()
