"""Converters from other labs' published robot data into proleg robot files.

    terresoro: read_terresoro(mat) -> PrimitiveStats; robot_toml(stats) -> str
               (python -m proleg.convert.terresoro IN.mat OUT.toml; needs the [terresoro] extra)
"""
