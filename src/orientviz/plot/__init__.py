"""orientviz.plot"""
