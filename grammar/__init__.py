"""Package data: the Lark grammar of the MTSA FSP dialect (``fsp.lark``).

Installed as ``iterplan_compiler.grammar``; load it with
``importlib.resources.files("iterplan_compiler.grammar") / "fsp.lark"``.
"""
