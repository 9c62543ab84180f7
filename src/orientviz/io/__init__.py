"""orientviz.io"""
