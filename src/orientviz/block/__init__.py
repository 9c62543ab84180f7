"""orientviz.block"""
